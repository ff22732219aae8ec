"""Everything the dashboard shows of the EtherCAT line, assembled: the 3D line, the Line and
Slave tabs, the Line controls, and focus (a click on a device, or a scenario ``Focus`` event:
its panels pick it and the camera moves toward it).

Focus picks the device in the Slave tab, the Slave actions form and the Objects tab of the
page that clicked (each page keeps its own pick, app/ui/panels/client_pick.py), and tells that
browser where to look; a scenario's focus picks it on every page and also opens the device's
tab (the dashboard does, app/ui/tab_switch.py).
A click (and "Show the whole line") moves the camera of the browser that clicked only: each
operator of a rig looks where they want (docs/dashboard.md "Several browsers"). A scenario's
focus moves every browser's, and the caption with it: a demo follows the narration.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np
import viser

from app.runtime import Frame, Runtime
from app.ui.commands import CommandSender, notify
from app.ui.label_fit import View
from app.ui.line.camera import send_pose
from app.ui.line.controls import LineControls
from app.ui.line.focus_labels import FocusLabels
from app.ui.line.master_panel import MasterPanel
from app.ui.line.scene import Box, LineScene
from app.ui.line.slave_panel import SlavePanel
from app.ui.line.style import LINE_CSS
from devices.events import Event

logger = logging.getLogger(__name__)

CAMERA_FOV_DEG = 50.0
CAMERA_RISE = 0.12  # camera height over the centre, per unit of distance
CAMERA_MARGIN = 0.4
FOCUS_MIN_W = 9.0  # a focused device fills at most this much scene width
# A click's pointer-up makes the browser send its own camera back; a move sent at once loses
# that race (seen: the camera stays), so a move after a click waits this long.
CLICK_SETTLE_S = 0.3
# A page reports the initial camera back through its own matrices (seen: off by ~1e-15).
INITIAL_ATOL = 1e-4
CAPTION_ROOM = 0.6  # above the line, for a scenario caption
# The camera looks from above, so the framed box leaves ~45 px free under the axes at 1280 x
# 720 and only a few above the line: a caption of three lines (app/ui/dashboard.py) did not fit
# there. Looking this much higher moves the picture down into that free room; a larger
# CAPTION_ROOM would instead zoom out, and the labels of the line would run into each other
# (tests/app/test_line_labels.py). tests/app/test_caption.py checks both ends.
CAPTION_LIFT = 1.4
CAPTION_GAP = 0.1  # from the top of what the caption stands above to its bottom
# Above a focused device, for three caption lines at the focus zoom (~50 px a unit at 1280 x
# 720): a focused view is fitted to the width, so this only moves the picture down a little.
FOCUS_CAPTION_ROOM = 1.2


def camera_for(box: Box, aspect: float, margin: float = CAMERA_MARGIN, lift: float = 0.0,
               ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(position, look_at) that fit ``box`` (front plane) into a view of ``aspect``, looking
    ``lift`` scene units above its centre."""
    half_tan = math.tan(math.radians(CAMERA_FOV_DEG) / 2)
    width, height = box.x_max - box.x_min, box.z_max - box.z_min
    distance = 1.0 + max((width / 2 + margin) / (half_tan * aspect),
                         (height / 2 + margin) / half_tan)
    centre = ((box.x_min + box.x_max) / 2, 0.0, (box.z_min + box.z_max) / 2 + lift)
    return (centre[0], -distance, centre[2] + distance * CAMERA_RISE), centre


def focus_frame(box: Box, ceiling: float | None = None) -> tuple[Box, tuple[float, float]]:
    """What a focus on a device of ``box`` frames, and where the caption goes: centred above
    the device and above ``ceiling``, the highest part of the scene over it (LineScene.top_over;
    default: the device's top), with room for it in the framed box. Placed above the whole
    line, the caption was out of every focused view, so a demo viewer lost the narration at
    each focus step; placed right on a row 2 device it covered cable 1 and its label."""
    width = max(box.x_max - box.x_min, FOCUS_MIN_W)
    centre = (box.x_min + box.x_max) / 2
    top = box.z_max if ceiling is None else max(ceiling, box.z_max)
    framed = Box(centre - width / 2, centre + width / 2, box.z_min, top + FOCUS_CAPTION_ROOM)
    return framed, (centre, top + CAPTION_GAP)


def focus_target(target: str) -> str:
    """``trscat`` or ``cpx:2`` (device:module) -> the device id."""
    return target.split(":", 1)[0].split("/", 1)[0]


class LineView:
    def __init__(self, server: viser.ViserServer, sender: CommandSender, frame: Frame,
                 master_id: str, rail_lengths: Mapping[str, float],
                 actions: Mapping[str, Mapping[str, Any]], side: Any,
                 control_tab: Callable[[str, Any], Any], aspect: float,
                 kinds: Mapping[str, str] | None = None, *,
                 runtime: Runtime, view_height_px: float = 670.0) -> None:
        """``kinds``: each device's kind, which sorts its actions into operation and faults
        (app.classroom.roles); ``runtime``: the models asked which actions a target takes;
        ``aspect`` and ``view_height_px``: the 3D view of the layout screenshots are taken
        at, which a scenario's focus fits the labels to (app/ui/line/focus_labels.py)."""
        self._server = server
        self._sender = sender
        self.master_id = master_id
        self._aspect = aspect
        # The Objects tab follows: (device, the clicking page, or None: every page)
        self.on_select: Callable[[str, viser.ClientHandle | None], None] | None = None
        # The dashboard's caption label follows the camera: (x, z) of its bottom centre.
        self.on_caption_moved: Callable[[tuple[float, float]], None] | None = None
        self.scene = LineScene(server, frame.snapshot, master_id, rail_lengths, self.focus,
                               self._cable_clicked)
        self.labels = FocusLabels(server, aspect * view_height_px, view_height_px,
                                  math.radians(CAMERA_FOV_DEG))
        order = self.scene.order
        gui = server.gui
        with side.add_tab("Line", viser.Icon.TOPOLOGY_STAR_3):
            gui.add_html(LINE_CSS)
            whole = gui.add_button("Show the whole line", icon=viser.Icon.ZOOM_OUT)
            self.master = MasterPanel(server, sender, master_id)
        with side.add_tab("Slave", viser.Icon.CPU_2):
            gui.add_html(LINE_CSS)
            self.slave = SlavePanel(server, [d for d in order if d not in rail_lengths] +
                                    [d for d in order if d in rail_lengths])
        with control_tab("Line", viser.Icon.TOPOLOGY_STAR_3):
            self.controls = LineControls(server, sender, master_id, order, actions,
                                         frame.snapshot.get("devices") or {},
                                         list(rail_lengths), kinds or {}, runtime)
        self.focused: str | None = None
        self.home: Box = self.scene.bounds()  # what "Show the whole line" frames (dashboard)
        # The view a scenario's focus shares (None: none): the labels follow it for every
        # page (_share_view), so a page that joins during it is sent it too (_joined).
        self._shared_box: Box | None = None
        server.on_client_connect(self._joined)

        @whole.on_click
        def _(event: viser.GuiEvent) -> None:
            self.show_all(event.client)

        self.slave.on_pick = lambda client, device: self.focus(client, device, move=False)

    # ---- geometry ---------------------------------------------------------------------------
    def bounds(self) -> Box:
        return self.scene.bounds()

    def drives_off_line(self, drive_ids: Iterable[str], snapshot: Mapping[str, Any],
                        ) -> list[str]:
        """The drives the line does not draw (the line draws a drive's EtherCAT side)."""
        devices = snapshot.get("devices") or {}
        on_line = {str((devices.get(d) or {}).get("drive")) for d in self.scene.order}
        return [d for d in drive_ids if d not in on_line]

    def frame_initial_camera(self, axes_bottom: float | None, min_width: float,
                             fov: float) -> tuple[float, float, float]:
        """Frame the line, the axes down to ``axes_bottom`` (at least ``min_width`` wide)
        and room for a caption; that is also what "Show the whole line" comes back to."""
        box = self.bounds()
        if axes_bottom is not None:
            box = Box(box.x_min, max(box.x_max, min_width), axes_bottom, box.z_max)
        self.home = Box(box.x_min, box.x_max, box.z_min, box.z_max + CAPTION_ROOM)
        position, look_at = camera_for(self.home, self._aspect, lift=CAPTION_LIFT)
        cam = self._server.initial_camera
        cam.fov = fov
        cam.look_at = look_at
        cam.position = position
        cam.up = (0.0, 0.0, 1.0)
        return look_at

    # ---- focus ----------------------------------------------------------------------------
    def focus(self, client: viser.ClientHandle | None, device: str, move: bool = True) -> None:
        """Pick ``device`` in the panels and move the camera toward it: ``client``'s (a
        click: its page's panels only), every browser's when None (a scenario's focus
        step)."""
        if device not in self.scene.bodies:
            logger.info("focus on %r: not a device of the line", device)
            return
        self.focused = device
        if device != self.master_id:
            self.slave.select(device, client)
            self.controls.select(device, client)
            if self.on_select is not None:
                self.on_select(device, client)
            where = "tabs Slave and Objects (left), Line (right)"
        else:
            where = "tab Line (left and right)"
        box = self.scene.focus_box(device)
        if move and box is not None:
            target, caption = self.focus_view(box)
            if client is None:
                self.move_camera(target, caption=caption)
                self._share_view(self.labels.view(*camera_for(target, self._aspect)))
                self._shared_box = target
            else:
                self._share_view(None)  # this page leaves the view the others share
                # The caption stays where the scenario put it: it is every page's.
                timer = threading.Timer(CLICK_SETTLE_S, self.move_camera, (target, 0.0, None),
                                        {"client": client})
                timer.daemon = True
                timer.start()
        notify(client, f"{device} selected", f"its panels: {where}")

    def _share_view(self, view: View | None) -> None:
        """Every browser shares ``view`` (a scenario's focus; None: no longer): the master's
        screen texts grow with its zoom, and the labels its edges would cut go."""
        master = self.scene.master
        if view is None:
            self._shared_box = None
            master.zoom(None)
            self.labels.release()
            return
        master.zoom(view.project(master.screen_centre)[2] or None)
        self.labels.focus(view)

    def focus_camera(self, device: str, aspect: float,
                     ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(position, look_at) a focus on ``device`` gives a view of ``aspect`` (tests)."""
        box = self.scene.focus_box(device)
        assert box is not None, device
        return camera_for(self.focus_view(box)[0], aspect)

    def focus_view(self, box: Box) -> tuple[Box, tuple[float, float]]:
        """focus_frame for ``box``, the caption above what the view shows over the device:
        everything within the framed width (the caption is as wide as the view at most)."""
        width = max(box.x_max - box.x_min, FOCUS_MIN_W) / 2 + CAMERA_MARGIN
        centre = (box.x_min + box.x_max) / 2
        return focus_frame(box, self.scene.top_over(centre - width, centre + width, box.z_max))

    @property
    def home_caption(self) -> tuple[float, float]:
        """(x, z) of the caption's bottom centre in the whole line's view: above the line."""
        return (self.home.x_min + self.home.x_max) / 2, self.bounds().z_max + CAPTION_GAP

    def show_all(self, client: viser.ClientHandle | None = None) -> None:
        """The whole line in ``client``'s view (its button), every browser's when None."""
        self._share_view(None)
        if client is not None:
            self.move_camera(self.home, CAPTION_LIFT, client=client)
        else:
            self.move_camera(self.home, CAPTION_LIFT, self.home_caption)

    async def _joined(self, client: viser.ClientHandle) -> None:
        """A page that joins while a scenario's focus is shared looks where the others do,
        from the moment its own initial camera is applied: viser's client applies the
        server's initial camera after its first camera report (the one that makes it a
        client) and overwrites any move sent before (tests/app/test_camera_per_browser.py).
        Async: viser awaits it on its loop before it passes that first report, and every
        later one, to the camera callbacks, so none is missed (a def runs on the pool)."""
        waiting = True

        async def reported(camera: viser.CameraHandle) -> None:
            nonlocal waiting
            if not waiting or not self._at_initial_camera(camera):
                return
            waiting = False  # once: a later "Reset view" is the user's
            box = self._shared_box
            if box is not None:
                self.move_camera(box, client=client)

        client.camera.on_update(reported)

    def _at_initial_camera(self, camera: viser.CameraHandle) -> bool:
        """The page reports the server's initial camera: it has applied it."""
        initial = self._server.initial_camera
        return bool(np.allclose(camera.position, initial.position, atol=INITIAL_ATOL)
                    and np.allclose(camera.look_at, initial.look_at, atol=INITIAL_ATOL))

    def move_camera(self, box: Box, lift: float = 0.0,
                    caption: tuple[float, float] | None = None,
                    client: viser.ClientHandle | None = None) -> None:
        """``client``'s camera onto ``box`` (every browser's when None), each fitted to its
        own 3D view (the canvas between the panels, whatever the window's size);
        ``caption``: where the scenario caption goes for that view."""
        if caption is not None and self.on_caption_moved is not None:
            self.on_caption_moved(caption)
        clients = [client] if client is not None else self._server.get_clients().values()
        for each in clients:
            try:
                position, look_at = camera_for(box, self._client_aspect(each), lift=lift)
                send_pose(each, position, look_at)  # not viser's setters: they may not send
            except Exception:  # a browser that just left
                logger.debug("camera move for client %s failed", each.client_id,
                             exc_info=True)

    def _client_aspect(self, client: viser.ClientHandle) -> float:
        """The browser's own 3D view (its canvas between the panels); before its first camera
        message, the 1280 x 720 layout's."""
        camera = client.camera
        if camera.update_timestamp == 0.0 or camera.image_height <= 0:
            return self._aspect
        return camera.aspect

    def add_events(self, events: Iterable[Event]) -> None:
        """Scenario ``Focus`` events (record kind "focus", key ``target``)."""
        for event in events:
            if event.kind == "focus":
                target = str(getattr(event, "target", "") or "")
                if target:
                    self.focus(None, focus_target(target))

    def _cable_clicked(self, client: viser.ClientHandle | None, index: int,
                       plugged: bool) -> None:
        verb = "pull_cable" if plugged else "plug_cable"
        self._sender.send(client, self.master_id, verb, {"cable": index})

    # ---- per frame (dashboard thread) -----------------------------------------------------
    def update(self, frame: Frame) -> None:
        devices = frame.snapshot.get("devices") or {}
        master = devices.get(self.master_id) or {}
        self.scene.update(frame.snapshot, frame.t_us)
        self.master.update(master, frame.t_us)
        self.slave.update(devices)
        self.controls.update(master, devices)
        self.labels.refresh()  # after the rails and axes too: the dashboard updates them first
