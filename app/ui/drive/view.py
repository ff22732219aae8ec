"""Everything the dashboard shows of the rig's servo drives, assembled in one place.

- 3D: one axis per drive under the rails (``axis_scene``);
- left panel: a "Drive" tab (state, live plots, status words bit by bit, the drive's log) and,
  when the drives have CANopen nodes, a "CANopen" tab (status, bus monitor, PDO mapping);
- control panel: the drive's controls (``drive_panel``) and the small CANopen master.

The panels show one drive at a time (a "Servo drive" picker appears when the rig has several);
every drive gets its axis. The dashboard thread calls :meth:`DriveView.update` with each new
frame and :meth:`DriveView.tick` about 30 times a second; the plots sample in the simulation
thread (``plots.DriveSampler``).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping
from typing import Any

import viser

from app.runtime import Frame, Runtime
from app.ui.commands import CommandSender
from app.ui.drive.axis_jam import AxisJam
from app.ui.drive.axis_scene import AXIS_HEIGHT, AXIS_SPACING, AXIS_TOP, AxisScene
from app.ui.drive.canopen_panel import CanOpenMaster, CanOpenMonitor
from app.ui.drive.drive_panel import DrivePanel
from app.ui.drive.drive_state import DriveStatePanel, StatusWordsPanel
from app.ui.drive.plots import DrivePlots, DriveSampler
from app.ui.drive.style import DRIVE_CSS
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import from_user
from devices.events import Event

logger = logging.getLogger(__name__)


def axes_height(drives: int) -> float:
    """Height of the 3D block that ``drives`` axes take, stacked downwards."""
    return AXIS_HEIGHT + (drives - 1) * AXIS_SPACING if drives else 0.0


def companion(snapshot: Mapping[str, Any], drive_id: str, kind: str | None = None,
              key: str | None = None) -> tuple[str | None, dict[str, Any]]:
    """A device that serves ``drive_id`` on a fieldbus (its snapshot names the drive), by kind
    or by a key its snapshot has: the CANopen node, the EtherCAT slave."""
    for device_id, snap in (snapshot.get("devices") or {}).items():
        if not isinstance(snap, Mapping) or snap.get("drive") != drive_id:
            continue
        if (kind is None or snap.get("kind") == kind) and (key is None or key in snap):
            return device_id, dict(snap)
    return None, {}


def bus_companions(snapshot: Mapping[str, Any], drive_id: str) -> tuple[str | None, str | None]:
    """The device ids of ``drive_id``'s CANopen node and EtherCAT slave (None: it has none)."""
    return (companion(snapshot, drive_id, kind="canopen")[0],
            companion(snapshot, drive_id, kind="servo_ecat")[0])


class DriveView:
    def __init__(self, server: viser.ViserServer, runtime: Runtime, sender: CommandSender,
                 described: Mapping[str, Mapping[str, Any]], drive_ids: list[str],
                 side: Any, top_z: float, length: float,
                 axis_ids: list[str] | None = None) -> None:
        """``side`` is the left panel (tabs are added to it); the controls go into the
        current GUI container; the axes hang from ``top_z`` downwards, ``length`` wide, one
        per drive of ``axis_ids`` (default: every drive; a drive drawn in the EtherCAT line
        has none)."""
        self._server = server
        self._runtime = runtime
        self.drive_ids = list(drive_ids)
        self.selected = self.drive_ids[0]
        snapshot = runtime.frame.snapshot
        self._buses = {d: bus_companions(snapshot, d) for d in self.drive_ids}
        self._nodes = {d: node for d, (node, _) in self._buses.items()}
        gui = server.gui
        self._picker = None
        if len(self.drive_ids) > 1:
            self._picker = gui.add_dropdown("Servo drive", tuple(self.drive_ids))
        gui.add_html(DRIVE_CSS)  # in each tab: an inactive tab's content is not mounted
        self.controls = DrivePanel(server, runtime, sender, lambda: self.selected,
                                   described[self.selected]["actions"], self.drive_ids)
        self.master: CanOpenMaster | None = None
        if any(self._nodes.values()):
            self.master = CanOpenMaster(server, runtime, sender,
                                        lambda: self._nodes.get(self.selected))
        self.sampler = DriveSampler(self._selected_snapshot, loads=lambda: runtime.rig.loads)
        runtime.add_step_listener(self.sampler.on_step,
                                  quiet_until=self.sampler.quiet_until)
        with side.add_tab("Drive", viser.Icon.ENGINE):
            gui.add_html(DRIVE_CSS)
            self.state = DriveStatePanel(server)
            self.plots = DrivePlots(server, self.sampler)
            self.words = StatusWordsPanel(server)
        self.canopen: CanOpenMonitor | None = None
        if self.master is not None:
            with side.add_tab("CANopen", viser.Icon.NETWORK):
                gui.add_html(DRIVE_CSS)
                self.canopen = CanOpenMonitor(server)
        instructor = instructor_for(server)
        # No injected cause in a classroom's shared scene; the instructor's own draws the jam.
        self.scenes = {d: AxisScene(server, d, top_z - AXIS_TOP - i * AXIS_SPACING, length,
                                    instructor.shared)
                       for i, d in enumerate(self.drive_ids if axis_ids is None else axis_ids)}
        self._jams = instructor.scene_part(
            lambda client: {d: AxisJam(client, scene) for d, scene in self.scenes.items()})

        if self._picker is not None:
            picker = self._picker

            @picker.on_update
            def _(event: viser.GuiEvent) -> None:
                if from_user(event) and picker.value in self.drive_ids:
                    self.select(picker.value)

    # ---- selection ----------------------------------------------------------------------
    def select(self, drive_id: str) -> None:
        self.selected = drive_id
        self.sampler.reset()
        self.controls.forget()
        if self.master is not None:
            self.master.forget()

    def focus(self, drive_id: str) -> None:
        """A scenario's focus step on a drive: the panels and the picker show it."""
        if drive_id == self.selected:
            return
        self.select(drive_id)
        if self._picker is not None:
            self._picker.value = drive_id

    def _selected_snapshot(self) -> Mapping[str, Any] | None:
        """Simulation thread (the sampler): the selected drive's snapshot, taken now."""
        device = self._runtime.rig.devices.get(self.selected)
        return device.snapshot() if device is not None else None

    def stop(self) -> None:
        self.sampler.active = False

    # ---- per frame (dashboard thread) ---------------------------------------------------
    def add_events(self, events: Iterable[Event]) -> None:
        mine = set(self.drive_ids)
        self.words.log.add(e for e in events if e.device in mine)

    def new_run(self) -> None:
        """A scenario load: no drive's rows of the previous run stay in the Drive log, nor
        its samples in the plots (a paused rig takes no step that would clear them)."""
        self.words.log.clear()
        self.sampler.new_run()

    def update(self, frame: Frame) -> None:
        devices = frame.snapshot.get("devices") or {}
        for drive_id, scene in self.scenes.items():
            scene.update(drive_id, devices.get(drive_id) or {}, frame.t_us)
        for jams in self._jams.each():
            try:
                for drive_id, jam in jams.items():
                    jam.show(devices.get(drive_id) or {})
            except Exception:  # a page that just left: forgotten by its disconnect
                logger.debug("instructor's jammed load not drawn", exc_info=True)
        snap = dict(devices.get(self.selected) or {})
        node, slave = (devices.get(i) if i else None for i in self._buses[self.selected])
        self.state.update(self.selected, snap, frame.t_us, node, slave)
        self.words.update(self.selected, snap)
        self.controls.update(snap, devices)
        if self.canopen is not None:
            node_id = self._nodes.get(self.selected) or ""
            self.canopen.update(node_id, devices.get(node_id) or {}, snap)
        if self.master is not None:
            self.master.update(devices.get(self._nodes.get(self.selected) or "") or {})

    def tick(self, now: float, t_us: int) -> None:
        self.plots.update(now, t_us)
