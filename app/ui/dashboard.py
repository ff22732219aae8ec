"""The viser dashboard of a rig: 3D DIN rail, control panel, state, event log, objects.

Threading (docs/dashboard.md): the runtime's simulation thread owns the models. viser runs
callbacks in its thread pool, or on its event loop (the controls that are device values,
``app.ui.panels.widgets.Synced``: they must not block); they only queue commands
(``app.ui.commands``). The dashboard has one update thread that, woken by each frame the
runtime publishes (about 30 a second, and one right after a command ran), reads the latest
frame and new events, writes what changed into the server-level handles inside
``server.atomic()``, so every browser sees the same rig and one frame's changes arrive
together, and flushes viser's send window, so a click's answer leaves at once (benchmark 2,
docs/performance.md).
"""

from __future__ import annotations

import logging
import math
import textwrap
import threading
import time
import urllib.parse
from collections.abc import Callable, Mapping
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import viser
import viser.theme

from app.runtime import Runtime
from app.ui.commands import CommandSender
from app.ui.drive.view import DriveView, axes_height
from app.ui.glyphs import warm_glyphs
from app.ui.line.view import LineView, focus_target
from app.ui.panels.client_pick import resend_overwritten
from app.ui.panels.control import ControlPanel, FaultOption
from app.ui.panels.event_log import EventLogPanel
from app.ui.panels.modules import ModulePanel
from app.ui.panels.object_dictionary import ObjectDictionaryPanel
from app.ui.panels.per_client import instructor_for
from app.ui.panels.state import StatePanel
from app.ui.panels.widgets import short_label_css
from app.ui.rail_power import RailPowers
from app.ui.rail_scene import BODY_D, BODY_H, RailScene, rail_length
from app.ui.runs import RunSplitter
from app.ui.style import CSS
from app.ui.tab_switch import TabSwitcher, tab_for
from devices.device import Action
from devices.events import US_PER_S, Caption, Event, Focus

logger = logging.getLogger(__name__)

UPDATE_HZ = 30.0
RIGHT_WIDTH = 320  # viser's control_width="medium"
LEFT_WIDTH = 400
MIN_FRAMED_SLOTS = 8  # the camera frames at least this many slots: a short rail stays put
# The 3D view between the docked panels of a 1280x720 window is about 580 x 670 px.
VIEW_HEIGHT_PX = 670
VIEW_ASPECT = (1280 - LEFT_WIDTH - RIGHT_WIDTH) / VIEW_HEIGHT_PX
CAMERA_MARGIN = 0.4
CAMERA_RISE = 0.12  # camera height over the rail centre, per unit of distance
RAIL_SPACING = BODY_H + 2.0  # vertical distance between the rails of several couplers
AXIS_GAP = 1.1  # from the lowest rail's bottom to the servo axes (its LED legend in between)
CAMERA_FOV_DEG = 50.0

# A screen label keeps its size on screen: one line of the longest scenario caption (236
# characters) was twice as wide as the 3D view between the panels, so both ends were under
# them. Lines of at most CAPTION_LINE characters at CAPTION_SCALE (about 7 px a character,
# tests/app/label_boxes.py) stay inside the ~560 px view with room to spare.
CAPTION_LINE = 76
CAPTION_SCALE = 1.0


def caption_lines(text: str) -> str:
    """A scenario caption broken at spaces into lines of at most CAPTION_LINE characters (a
    longer word keeps a line of its own; hyphens and underscores stay: "0xF700 / 0xF701",
    "NOT_SYNCHRONIZED" are what the trainee looks up)."""
    return textwrap.fill(" ".join(text.split()), CAPTION_LINE, break_long_words=False,
                         break_on_hyphens=False)


TITLE_SVG = (
    "<svg xmlns='http://www.w3.org/2000/svg' width='132' height='32'>"
    "<text x='2' y='23' font-family='DejaVu Sans, Arial, sans-serif' font-size='20' "
    "font-weight='700' fill='#1f4f8f'>FieldRig</text></svg>")


def fault_options() -> list[FaultOption]:
    """The fault dropdown's rows, straight from the coupler's tables (seed 000 §7.5, §7.6)."""
    from devices.fastcat.alarms import CODE_TABLES

    return [FaultOption(row.table, row.code, row.symbol, row.description,
                        on_coupler=row.on_coupler, on_module=row.names_module)
            for table in CODE_TABLES.values() for row in table.values()]


def _param_range(action: Action | None, default: tuple[int, int]) -> tuple[int, int]:
    """(low, high) of an action's first parameter, e.g. set_rotary(value 1..15)."""
    param = action.params[0] if action is not None and action.params else None
    if param is None or param.low is None or param.high is None:
        return default
    return int(param.low), int(param.high)


@dataclass(frozen=True)
class _Panels:
    control: ControlPanel
    modules: ModulePanel
    state: StatePanel
    log: EventLogPanel
    objects: ObjectDictionaryPanel


def _kind_ids(described: Mapping[str, Mapping[str, Any]], kind: str) -> list[str]:
    return [device_id for device_id, info in described.items() if info["kind"] == kind]


class Dashboard:
    def __init__(self, server: viser.ViserServer, runtime: Runtime,
                 draw_unwatched: bool = False, scenarios: Path | None = None,
                 glyphs: str = "") -> None:
        self.server = server
        self.runtime = runtime
        # Before any other label: the atlas order that makes two screenshot runs' text
        # pixels the same (app/ui/glyphs.py); a served dashboard does without.
        if glyphs:
            warm_glyphs(server.scene, glyphs)
        # False: no view is computed while no browser is connected (the thread only takes
        # events). True for a driver that waits on rendered_seq before any page is open (the
        # screenshot tool steps a paused rig and waits for each frame to be drawn); such a
        # driver's pages must not hang on wall time, so the drive plots then go with every
        # drawn frame instead of every SEND_PERIOD_S (app/ui/drive/plots.py).
        self.draw_unwatched = draw_unwatched
        described = runtime.rig.describe()
        self.fastcat_ids = _kind_ids(described, "fastcat")
        self.master_id = next(iter(_kind_ids(described, "master")), None)
        self.drive_ids = _kind_ids(described, "servo")
        # The EtherCAT line (app/ui/line) when the master has slaves besides one FastCAT.
        master_snap = self._device_snap(runtime.frame.snapshot, self.master_id)
        self._line_wanted = len(master_snap.get("slaves") or []) > 1
        self._line: LineView | None = None
        self._side: Any = None  # the left panel, once built
        self._control_tabs: Any = None  # FastCAT | Servo drive in the control panel
        # The panels drive the first coupler; every coupler gets its rail in the 3D view.
        self.device_id = self.fastcat_ids[0] if self.fastcat_ids else None
        self._sender = CommandSender(runtime)
        # What names an injected cause or picks a fault is built per instructor connection
        # with a token (app/ui/panels/per_client.py); the first views to update it redraw.
        self.instructor = instructor_for(server, self._sender.gate.access)
        self.instructor.on_built = self._redraw
        self._stop = threading.Event()
        self._wake = threading.Event()  # set by the runtime's frame listener
        self._thread: threading.Thread | None = None
        self._event_seq = 0
        # The last frame whose views are written: set at the end of a tick, as tests and the
        # screenshot tool read the widgets as soon as it moves (rendered_seq).
        self._frame_seq = -1
        self._t_us = -1
        self._events_untold = False  # events taken while no browser was there (take_events)
        # Redraws asked (an instructor's parts were built: write the views again) and the
        # last one a tick wrote: a count, as a flag reset by the tick lost a redraw asked
        # between its read and its reset (on a paused rig nothing else redraws).
        self._redraws = self._redrawn = 0
        self._redraw_lock = threading.Lock()
        self._lock = threading.Lock()  # one tick at a time (thread, tests calling tick())
        self._failing: set[str] = set()  # views whose last update raised (_view_update)
        self._tabs = TabSwitcher(server)  # a scenario focus step opens its device's tab
        self._configure_look()
        self._panels: _Panels | None = None
        if self.device_id is not None:
            self._panels = self._build_gui(described, self.device_id)
        elif not self.drive_ids:  # other device kinds have no view yet: say so, do not fail
            logger.warning("rig '%s' has no FastCAT and no servo drive: the dashboard shows "
                           "nothing", runtime.rig.name)
            self.server.gui.add_markdown(f"Rig **{runtime.rig.name}** has no FastCAT coupler "
                                         "and no servo drive: this dashboard shows those only.")
        # In the line only the first coupler has a rail (row 1); the others are line bodies.
        railed = self.fastcat_ids[:1] if self._line_wanted else self.fastcat_ids
        # A module's supply is a hidden cause: with a token the shared rail draws every
        # module powered and each instructor connection the ones switched off over it.
        self._scenes = [RailScene(server, d, z=-i * RAIL_SPACING, causes=self.instructor.shared)
                        for i, d in enumerate(railed)]
        self._rail_powers = RailPowers(self.instructor, self._scenes)
        for scene in self._scenes:
            scene.build_coupler()
        frame_slots = [len(self._device_snap(runtime.frame.snapshot, d).get("rail") or [])
                       for d in railed]
        if self._line_wanted and self.master_id is not None:
            self._line = self._build_line(described, dict(zip(railed, frame_slots,
                                                              strict=True)))
        # ---- servo drives (app/ui/drive): tabs, controls, one axis each under the rails ---
        self._drives: DriveView | None = None
        below = 0.0
        if self.drive_ids:
            rails, height = len(self._scenes), axes_height(len(self.drive_ids))
            if self._line is not None:  # under the line
                top = self._line.bounds().z_min - 0.3
                below = 0.0
            elif rails:  # under the lowest rail
                top = -(rails - 1) * RAIL_SPACING - BODY_H / 2 - AXIS_GAP
                below = AXIS_GAP + height
            else:  # where the rail would be
                top, below = BODY_H / 2, max(height - BODY_H, 0.0)
            self._drives = self._build_drives(described, top, max(frame_slots, default=0))
        # A rig with drives only frames their axes (as wide as an 8-slot rail).
        slots = max(frame_slots, default=MIN_FRAMED_SLOTS if self.drive_ids else 0)
        if self._line is not None:
            self._frame_line(top - axes_height(len(self._axis_ids())) if self._drives else None)
        else:
            self._frame_camera(slots, max(len(self._scenes), 1), below)
        center = self._camera_center
        # Scenario narration (Caption events), above the rail: what a screenshot should say.
        caption_z = (BODY_H / 2 + 1.3 if self._line is None
                     else self._line.bounds().z_max + 0.1)
        self._caption = server.scene.add_label(
            "/caption", "", position=(center[0], -BODY_D, caption_z),
            anchor="bottom-center", font_screen_scale=CAPTION_SCALE, visible=False)
        if self._line is not None:  # a focused view takes the caption above its device
            self._line.on_caption_moved = self._place_caption
        # ---- scenario player, code decoder (app/ui/panels/scenario_player.py, decoder.py) ----
        from app.ui.panels.decoder import DecoderPanel
        from app.ui.panels.scenario_player import ScenarioPlayerPanel

        with self._control_tab("Scenario", viser.Icon.PLAYER_PLAY):
            self.scenario_player = ScenarioPlayerPanel(server, runtime, own=scenarios)
        last_load = self.scenario_player.player.last_load
        self._runs = RunSplitter(last_load)  # where a load starts a new run in a batch
        self.decoder = DecoderPanel(server, runtime, self._side, last_load)
        # ---- end of scenario player, code decoder ----
        # The Fault and Alarm boxes' longest names whole: one style at the end of the control
        # panel (inside a folder it would be a row of it; the classroom's folder check counts).
        short = [*(self._panels.control.short_labels if self._panels else ()),
                 *(self._drives.controls.short_labels if self._drives else ())]
        if short:
            server.gui.add_html(short_label_css(short))

    # ---- construction -------------------------------------------------------------------
    def _configure_look(self) -> None:
        gui = self.server.gui
        image = viser.theme.TitlebarImage(
            image_url_light="data:image/svg+xml;utf8," + urllib.parse.quote(TITLE_SVG),
            image_url_dark=None, image_alt="FieldRig", href=None)
        gui.configure_theme(titlebar_content=viser.theme.TitlebarConfig(buttons=(), image=image),
                            dark_mode=False, show_logo=False, show_share_button=False,
                            brand_color=(31, 79, 143), control_width="medium")
        # The control panel's width is the theme's "medium" (20 em = 320 px). A set_width on
        # the main panel races with the theme message in the browser (seen: 300 or 320 px
        # from one load to the next), so the theme alone sets it.
        gui.main_panel.dock_right()
        self.server.scene.set_up_direction("+z")
        # Flat, even light from the front: LED colours read true, screenshots are stable.
        scene = self.server.scene
        scene.configure_environment_map(hdri=None)
        scene.configure_default_lights(enabled=False, cast_shadow=False)
        scene.add_light_ambient("/light/ambient", intensity=1.6)
        scene.add_light_directional("/light/front", intensity=1.4, position=(0.0, -10.0, 6.0))

    def _build_gui(self, described: Mapping[str, Mapping[str, Any]], device_id: str) -> _Panels:
        from devices.fastcat.catalog import CATALOG

        actions = described[device_id]["actions"]
        gui = self.server.gui
        gui.add_html(CSS)
        with self._control_tab("FastCAT", viser.Icon.CPU):
            control = ControlPanel(self.server, self._sender, device_id, fault_options(),
                                   _param_range(actions.get("set_rotary"), (1, 15)),
                                   self.master_id)
            modules = ModulePanel(self.server, self.runtime, self._sender, device_id, actions,
                                  list(CATALOG))
        side = self._side = gui.add_panel()
        with side.add_tab("State", viser.Icon.GAUGE):
            state = StatePanel(self.server)
            gui.add_markdown("**Event log**")
            # Every device's own events (the drives' alarms too), the master's via its log.
            log = EventLogPanel(self.server, {d: str(info["kind"]) for d, info in
                                              described.items() if d != self.master_id},
                                self._timestamp_fn(), self._scenario_title)
        with side.add_tab("Objects", viser.Icon.LIST_DETAILS):
            objects = ObjectDictionaryPanel(self.server, self.runtime, self._sender, device_id,
                                            self._od_ids(described, device_id))
        side.dock_left()
        side.set_width(LEFT_WIDTH)
        return _Panels(control, modules, state, log, objects)

    def _od_ids(self, described: Mapping[str, Mapping[str, Any]], first: str) -> list[str]:
        """Devices the Objects tab offers: ``first``, then the line's slaves with an object
        dictionary (TRS-CAT, CPX-E-EC, the drive's CoE side)."""
        if not self._line_wanted:
            return [first]
        devices = self.runtime.rig.devices
        others = [d for d, info in described.items()
                  if d != first and {"read_object", "write_object"} <= set(info["actions"])
                  and hasattr(devices.get(d), "od")]
        return [first, *others]

    def _control_tab(self, label: str, icon: Any) -> AbstractContextManager[Any]:
        """A tab of the control panel when the rig has drives too, else the panel itself."""
        if not (self.drive_ids and self.fastcat_ids) and not self._line_wanted:
            return nullcontext()
        if self._control_tabs is None:
            self._control_tabs = self.server.gui.add_tab_group()
        return self._control_tabs.add_tab(label, icon)

    def _build_drives(self, described: Mapping[str, Mapping[str, Any]], top: float,
                      slots: int) -> DriveView:
        """The servo drives' tabs, controls and axes (app/ui/drive, docs/dashboard.md)."""
        side = self._side
        if side is None:  # no FastCAT: the drive tabs get the left panel to themselves
            self.server.gui.add_html(CSS)
            side = self._side = self.server.gui.add_panel()
        with self._control_tab("Servo drive", viser.Icon.ENGINE):
            view = DriveView(self.server, self.runtime, self._sender, described, self.drive_ids,
                             side, top, rail_length(max(slots, MIN_FRAMED_SLOTS)),
                             self._axis_ids())
        if self._panels is None:
            side.dock_left()
            side.set_width(LEFT_WIDTH)
        return view

    def _build_line(self, described: Mapping[str, Mapping[str, Any]],
                    slots: Mapping[str, int]) -> LineView:
        """The EtherCAT line: 3D, Line and Slave tabs, Line controls (app/ui/line)."""
        assert self.master_id is not None
        side = self._side
        if side is None:  # no FastCAT: the line gets the left panel
            self.server.gui.add_html(CSS)
            side = self._side = self.server.gui.add_panel()
            side.dock_left()
            side.set_width(LEFT_WIDTH)
        actions = {d: info["actions"] for d, info in described.items()}
        line = LineView(self.server, self._sender, self.runtime.frame, self.master_id,
                        {d: rail_length(n) for d, n in slots.items()}, actions, side,
                        self._control_tab, VIEW_ASPECT,
                        {d: str(info.get("kind", "")) for d, info in described.items()},
                        runtime=self.runtime, view_height_px=VIEW_HEIGHT_PX)
        if self._panels is not None:
            line.on_select = self._panels.objects.select
        return line

    def _axis_ids(self) -> list[str]:
        """Drives that get a 3D axis: not those the line draws (their EtherCAT side)."""
        if self._line is None:
            return list(self.drive_ids)
        return self._line.drives_off_line(self.drive_ids, self.runtime.frame.snapshot)

    def _frame_line(self, axes_bottom: float | None) -> None:
        """Frame the whole line (and the axes under it) between the docked panels."""
        assert self._line is not None
        bottom = axes_bottom if axes_bottom is not None and self._axis_ids() else None
        self._camera_center = self._line.frame_initial_camera(
            bottom, rail_length(MIN_FRAMED_SLOTS), math.radians(CAMERA_FOV_DEG))

    def _timestamp_fn(self) -> Callable[[int], str]:
        """The master logger's clock for device rows, so that all rows read alike."""
        from devices.master import twincat_timestamp

        master = self.runtime.rig.devices.get(self.master_id) if self.master_id else None
        epoch = getattr(master, "epoch", None)
        if epoch is None:  # no master in the rig: simulated seconds
            return lambda t_us: f"{t_us / US_PER_S:.3f} s"
        return lambda t_us: twincat_timestamp(epoch, t_us)

    def _frame_camera(self, slots: int, rails: int, below: float = 0.0) -> None:
        """Fit the rail(s) into the 3D view between the docked panels, looking at the front
        from slightly above (the top faces give depth; labels stay square to the eye).
        ``below``: height the servo axes add under the lowest rail."""
        length = rail_length(max(slots, MIN_FRAMED_SLOTS))
        height = BODY_H + (rails - 1) * RAIL_SPACING + below
        center = (rail_length(slots) / 2, 0.0, -(rails - 1) * RAIL_SPACING / 2 - below / 2)
        half_tan = math.tan(math.radians(CAMERA_FOV_DEG) / 2)
        distance = BODY_D / 2 + max((length / 2 + CAMERA_MARGIN) / (half_tan * VIEW_ASPECT),
                                    (height / 2 + CAMERA_MARGIN) / half_tan)
        cam = self.server.initial_camera
        cam.fov = math.radians(CAMERA_FOV_DEG)
        cam.look_at = center
        cam.position = (center[0], -distance, center[2] + distance * CAMERA_RISE)
        cam.up = (0.0, 0.0, 1.0)
        self._camera_center = center

    # ---- running ------------------------------------------------------------------------
    def start(self) -> None:
        # Runs in the simulation thread right after each publication: only a flag.
        self.runtime.add_frame_listener(lambda _frame: self._wake.set())
        # A browser that connects is shown the views at once, not at the next frame.
        self.server.on_client_connect(lambda _client: self._wake.set())
        self._thread = threading.Thread(target=self._run, name="fieldrig-dashboard",
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._drives is not None:
            self._drives.stop()
        if self._thread is not None:
            self._thread.join(timeout=5)

    def _run(self) -> None:
        # A frame wakes the thread at once (a command's frame is published as soon as it
        # ran); without one (a stopped simulation thread) it still updates at UPDATE_HZ, for
        # what runs on wall time (the Objects tab's refresh, the drive plots).
        period = 1.0 / UPDATE_HZ
        while not self._stop.is_set():
            self._wake.wait(period)
            self._wake.clear()
            if self._stop.is_set():
                break
            try:
                if not self.draw_unwatched and not self.server.get_clients():
                    # Nobody to show the views to: computing them was most of an idle served
                    # rig's dashboard cost. The logs still take every event (the journal is
                    # bounded), and the first tick with a browser draws the current frame.
                    self.take_events()
                    continue
                self.tick()
                # viser sends a window, then waits 1/60 s before looking for the next one
                # unless flushed: without this a click's answer could wait those 17 ms.
                self.server.flush()
            except Exception:  # a view bug must not freeze the dashboard for good
                logger.exception("dashboard update failed")

    def _scenario_title(self) -> str:
        """The loaded scenario's name, "" before any (the event log's new-run row, which every
        browser gets: a neutral title while an exercise runs on a rig with a token)."""
        return self.scenario_player.shown_title()

    @staticmethod
    def _device_snap(snapshot: Mapping[str, Any], device_id: str | None) -> dict[str, Any]:
        return dict((snapshot.get("devices") or {}).get(device_id or "", {}) or {})

    def tick(self) -> None:
        """One view update: new events into the log, changed values into the handles."""
        with self._lock:
            frame, panels = self.runtime.frame, self._panels
            with self.server.atomic():
                redraws = self._redraws  # first: one asked from here on is the next tick's
                events = self._take_events()
                # A view that failed runs again though the frame has not moved (a paused
                # rig): what its failure skipped is sent now, not when the frame next moves.
                fresh = frame.seq != self._frame_seq or frame.t_us != self._t_us or events \
                    or self._events_untold or redraws != self._redrawn or bool(self._failing)
                self._t_us, self._events_untold, self._redrawn = frame.t_us, False, redraws
                view = self._view_update
                if fresh:
                    snaps = [self._device_snap(frame.snapshot, d) for d in self.fastcat_ids]
                    for i, (scene, snap) in enumerate(zip(self._scenes, snaps, strict=True)):
                        view(f"rail {i + 1}", scene.update, snap, frame.t_us)
                    view("rail power", self._rail_powers.update, snaps)
                    if panels is not None:
                        main = snaps[0]
                        master = self._device_snap(frame.snapshot, self.master_id)
                        view("state", panels.state.update, main, master, frame.t_us)
                        view("control", panels.control.update, main)
                        view("modules", panels.modules.update, main)
                        view("log", panels.log.update, master)
                    if self._drives is not None:
                        view("drives", self._drives.update, frame)
                    if self._line is not None:
                        view("line", self._line.update, frame)
                if panels is not None:
                    view("objects", panels.objects.tick)
                if self._drives is not None:
                    view("drive plots", self._drives.tick, time.monotonic(), frame.t_us,
                         self.draw_unwatched)
                view("scenario player", self.scenario_player.update, frame)
                view("decoder", self.decoder.update)
                # frame or not: a paused rig sends none
                view("resend", resend_overwritten, self.server)
            self._frame_seq = frame.seq

    def _view_update(self, name: str, update: Callable[..., Any], *args: Any) -> None:
        """One view's part of a tick. Its failure is logged once until it works again and the
        views after it still update: one panel's bug left the Line tab, the drive panels and
        an instructor's tables frozen for as long as it lasted. Until it works again every
        tick runs it (``tick``'s ``fresh``)."""
        try:
            update(*args)
        except Exception:
            if name not in self._failing:
                self._failing.add(name)
                logger.exception("dashboard view %r failed to update", name)
        else:
            self._failing.discard(name)

    def held(self) -> AbstractContextManager[Any]:
        """No view update while in it: a driver that steps the rig draws each step whole,
        its frame with the events the step journals after publishing it (a scenario's focus
        step: the screenshot tool, app/screenshots.py ``play``)."""
        return self._lock

    def _redraw(self) -> None:
        """New instructor widgets start from their defaults: the next tick writes them."""
        with self._redraw_lock:
            self._redraws += 1
        self._wake.set()

    def take_events(self) -> None:
        """The new events into the logs and the caption, without updating the views (no
        browser connected); the next :meth:`tick` updates them."""
        with self._lock:
            if self._take_events():
                self._events_untold = True

    def _take_events(self) -> list[Event]:
        self._event_seq, events = self.runtime.events_since(self._event_seq)
        split = self._runs.split(self._event_seq, events)
        run = events  # the current run's events
        if split is None:
            self._log_events(events)
        else:  # a scenario load: the logs and the caption start afresh where it happened
            old, run = split
            self._log_events(old)
            if self._panels is not None:
                self._panels.log.new_run()
            if self._drives is not None:
                self._drives.new_run()
            self._log_events(run)
            # The old run's narration is over, its captions in this batch too.
            self._caption.visible = False
        if self._line is not None:
            self._line.add_events(events)
        self._focus_tabs(run)
        captions = [e.text for e in run if isinstance(e, Caption)]
        if captions:
            self._caption.text = caption_lines(captions[-1])
            self._caption.visible = True
        return events

    def focus_tab(self, device: str) -> str | None:
        """The left panel's tab that shows ``device`` (None: no tab of its own here)."""
        line = self._line.scene.order if self._line is not None else ()
        return tab_for(device, master=self.master_id if self._line is not None else None,
                       coupler=self.device_id, line=line, drives=self.drive_ids)

    def _focus_tabs(self, events: list[Event]) -> None:
        """A scenario's focus step opens the focused device's tab in every browser (a demo
        follows the narration; a click in the 3D view only names the tabs, LineView.focus),
        and picks a drive in the drive panels."""
        focus = [e for e in events if isinstance(e, Focus) and e.device == "scenario"]
        if not focus:
            return
        device = focus_target(str(focus[-1].target))
        if self._drives is not None and device in self._drives.drive_ids:
            self._drives.focus(device)
        tab = self.focus_tab(device)
        if tab is not None:
            self._tabs.open(tab)

    def _log_events(self, events: list[Event]) -> None:
        if self._panels is not None:
            self._panels.log.add_events(events)
        if self._drives is not None:
            self._drives.add_events(events)

    def _place_caption(self, where: tuple[float, float]) -> None:
        self._caption.position = (where[0], -BODY_D, where[1])

    @property
    def caption(self) -> str:
        """The scenario caption shown above the rail ("" before the first one), on one line
        as the scenario wrote it."""
        return " ".join(str(self._caption.text).split("\n")) if self._caption.visible else ""

    def instructor_widgets(self) -> list[Any]:
        """The controls that make a fault or show one outright: a trainee's page does not
        show them (the classroom's trainee CSS, docs/classroom.md)."""
        found: list[Any] = []
        if self._panels is not None:
            found += self._panels.control.instructor_only
            found += self._panels.modules.instructor_only
        if self._drives is not None:
            found += self._drives.controls.instructor_only
        if self._line is not None:
            found += self._line.controls.instructor_only
        return found

    @property
    def objects(self) -> ObjectDictionaryPanel | None:
        """The Objects tab (tests)."""
        return self._panels.objects if self._panels is not None else None

    @property
    def line(self) -> LineView | None:
        """The EtherCAT line's part of the dashboard (tests)."""
        return self._line

    @property
    def drives(self) -> DriveView | None:
        """The servo drives' part of the dashboard (tests)."""
        return self._drives

    @property
    def rendered_seq(self) -> int:
        """Sequence number of the last frame written to the handles (tests wait on it)."""
        return self._frame_seq

    def scene_colors(self) -> dict[str, tuple[int, int, int]]:
        """LED colours shown for the first coupler (tests)."""
        return self._scenes[0].led_colors()

    def scene_slots(self) -> dict[int, str | None]:
        """Module types drawn on the first coupler's rail (tests)."""
        return self._scenes[0].drawn_slots()
