"""Everything the dashboard shows of the rig's servo drives, assembled in one place.

- 3D: one axis per drive under the rails (``axis_scene``);
- left panel: a "Drive" tab (state, live plots, status words bit by bit, the drive's log) and,
  when the drives have CANopen nodes, a "CANopen" tab (status, bus monitor, PDO mapping);
- control panel: the drive's controls (``drive_panel``) and the small CANopen master.

The panels show one drive at a time, each page the one it picked (a "Servo drive" picker
appears when the rig has several: app/ui/panels/client_pick.py); every drive gets its axis.
The dashboard thread calls :meth:`DriveView.update` with each new frame and
:meth:`DriveView.tick` about 30 times a second; the plots sample every drive in the simulation
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
from app.ui.drive.canopen_panel import CanOpenMaster, CanOpenMonitor, on_canopen
from app.ui.drive.drive_panel import DrivePanel
from app.ui.drive.drive_state import DriveStatePanel, StatusWordsPanel
from app.ui.drive.plots import DrivePlots, DriveSampler
from app.ui.drive.style import DRIVE_CSS
from app.ui.panels.client_pick import ClientPick, send_on
from app.ui.panels.per_client import instructor_for
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
        self._default = self.drive_ids[0]
        snapshot = runtime.frame.snapshot
        self._buses = {d: bus_companions(snapshot, d) for d in self.drive_ids}
        self._nodes = {d: node for d, (node, _) in self._buses.items()}
        gui = server.gui
        # Each page's own pick (app/ui/panels/client_pick.py): what the drive tabs show and
        # the controls command. Before, one page's pick switched every page's drive.
        self._pick: ClientPick | None = None
        if len(self.drive_ids) > 1:
            self._pick = ClientPick(server, gui.add_dropdown("Servo drive",
                                                             tuple(self.drive_ids)))
        per_page = self._pick is not None
        gui.add_html(DRIVE_CSS)  # in each tab: an inactive tab's content is not mounted
        self.controls = DrivePanel(server, runtime, sender, self._drive_of_client,
                                   described[self.selected]["actions"], self.drive_ids)
        self.master: CanOpenMaster | None = None
        if any(self._nodes.values()):
            self.master = CanOpenMaster(
                server, runtime, sender,
                lambda client: self._nodes.get(self._drive_of_client(client)))
        # Every drive sampled all along, so a page that picks one sees its last 20 s at once
        self.samplers = {d: DriveSampler(lambda d=d: self._snapshot_of(d),
                                         loads=lambda: runtime.rig.loads)
                         for d in self.drive_ids}
        for sampler in self.samplers.values():
            runtime.add_step_listener(sampler.on_step, quiet_until=sampler.quiet_until)
        with side.add_tab("Drive", viser.Icon.ENGINE):
            gui.add_html(DRIVE_CSS)
            self.state = DriveStatePanel(server, per_page)
            # Each drive's charts, the page's drive's shown (per page: _show_plots)
            self._plots = {d: DrivePlots(server, self.samplers[d], d == self._default)
                           for d in self.drive_ids}
            self.words = StatusWordsPanel(server, per_page)
        self.canopen: CanOpenMonitor | None = None
        if self.master is not None:
            with side.add_tab("CANopen", viser.Icon.NETWORK):
                gui.add_html(DRIVE_CSS)
                self.canopen = CanOpenMonitor(server, per_page)
        instructor = instructor_for(server)
        # No injected cause in a classroom's shared scene; the instructor's own draws the jam.
        self.scenes = {d: AxisScene(server, d, top_z - AXIS_TOP - i * AXIS_SPACING, length,
                                    instructor.shared)
                       for i, d in enumerate(self.drive_ids if axis_ids is None else axis_ids)}
        self._jams = instructor.scene_part(
            lambda client: {d: AxisJam(client, scene) for d, scene in self.scenes.items()})

        if self._pick is not None:
            self._pick.on_pick(self._picked)

    # ---- selection ----------------------------------------------------------------------
    @property
    def selected(self) -> str:
        """The drive a new page shows (the last pick for every page); the plots'."""
        return self._default

    def selected_for(self, client_id: int | None) -> str:
        """The drive ``client_id``'s page shows."""
        return self._pick.value_for(client_id) if self._pick is not None else self._default

    def _drive_of_client(self, client: viser.ClientHandle | None) -> str:
        return self.selected_for(client.client_id if client is not None else None)

    @property
    def sampler(self) -> DriveSampler:
        """The samples of the drive a new page shows."""
        return self.samplers[self._default]

    @property
    def plots(self) -> DrivePlots:
        """The charts of the drive a new page shows."""
        return self._plots[self._default]

    def _show_plots(self, drive_id: str, client: viser.ClientHandle | None) -> None:
        """``drive_id``'s charts on ``client``'s page (every page's when None), no other's."""
        for each, plots in self._plots.items():
            for chart in plots.charts:
                send_on(client, chart, "visible", each == drive_id)

    def _picked(self, client: viser.ClientHandle, drive_id: str) -> None:
        """A page picked a drive: its charts, and its forms take that drive's values."""
        self._show_plots(drive_id, client)
        self.controls.forget(client.client_id)
        if self.master is not None:
            self.master.forget(client.client_id)

    def select(self, drive_id: str) -> None:
        """Every page, and every page to come, shows ``drive_id``."""
        self._default = drive_id
        if self._pick is not None:  # also the pages that picked another on their own
            self._pick.set_all(drive_id)
            self._show_plots(drive_id, None)
        self.controls.forget()
        if self.master is not None:
            self.master.forget()

    def focus(self, drive_id: str) -> None:
        """A scenario's focus step on a drive: the panels and the picker show it."""
        if drive_id in self.drive_ids:
            self.select(drive_id)

    def _snapshot_of(self, drive_id: str) -> Mapping[str, Any] | None:
        """Simulation thread (a sampler): the drive's snapshot, taken now."""
        device = self._runtime.rig.devices.get(drive_id)
        return device.snapshot() if device is not None else None

    def stop(self) -> None:
        for sampler in self.samplers.values():
            sampler.active = False

    # ---- per frame (dashboard thread) ---------------------------------------------------
    def add_events(self, events: Iterable[Event]) -> None:
        mine = set(self.drive_ids)
        self.words.log.add(e for e in events if e.device in mine)

    def new_run(self) -> None:
        """A scenario load: no drive's rows of the previous run stay in the Drive log, nor
        its samples in the plots (a paused rig takes no step that would clear them)."""
        self.words.log.clear()
        for sampler in self.samplers.values():
            sampler.new_run()

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

        def data_of(drive_id: str) -> tuple[Mapping[str, Any], Any, Any]:
            node, slave = (devices.get(i) if i else None for i in self._buses[drive_id])
            return devices.get(drive_id) or {}, node, slave

        def node_of(drive_id: str) -> tuple[str, Mapping[str, Any], Mapping[str, Any]]:
            node_id = self._nodes.get(drive_id) or ""
            return node_id, devices.get(node_id) or {}, devices.get(drive_id) or {}

        self.state.update(self.selected_for, data_of, frame.t_us, self._runtime.modbus)
        self.words.update(self.selected_for, data_of)
        self.controls.update(snap, devices, self.selected_for if self._pick else None)
        if self.canopen is not None:
            self.canopen.update(self.selected_for, node_of, on_canopen(devices, self._nodes))
        if self.master is not None:
            self.master.update(lambda client_id: node_of(self.selected_for(client_id))[1])

    def tick(self, now: float, t_us: int, force: bool = False) -> None:
        """``force``: send new samples now, however soon after the last send."""
        shown = {self._default, *(self.selected_for(c) for c in self._server.get_clients())}
        for drive_id in shown:  # a drive picked later gets its samples at its first tick
            self._plots[drive_id].update(now, t_us, force)
