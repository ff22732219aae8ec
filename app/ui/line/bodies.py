"""The 3D bodies of the line besides the FastCAT rail: the master PC, a generic EtherCAT slave
(the drive's CoE side), and the base every body shares (header, state bar, LED legend).

Same conventions as the rail (``app.ui.rail_scene``): z up, the fronts face -y, sizes in
module widths. A body spans ``x0 .. x0 + width`` and ``z0 - BODY_H / 2 .. z0 + BODY_H / 2``.
Above it: a bar coloured by the slave's state as the master sees it (green OP, amber on the
way, red with an error flag, grey when not seen) and a header "position · address · state";
below it: the LEDs whose pattern a still picture cannot show, in words.

Labels keep one size on screen whatever the zoom (viser "screen" labels), so a text that
must stay inside its part (the master's screen, a module plate, the drive's front) is broken
onto lines (:func:`wrap`) rather than shrunk; tests/app/test_line_labels.py checks them at
the dashboard's default camera, the widest view.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import Any

import viser

from app.ui.label_fit import EM_PX
from app.ui.line.painter import FRONT_Y, Painter
from app.ui.rail_scene import BODY_D, BODY_H, PATTERN_WORDS, RGB
from devices.ethercat import AL_STATUS_ERROR_FLAG
from devices.master.view import dc_words, phase_text

BODY: RGB = (214, 219, 228)
BODY_OFF: RGB = (150, 152, 158)
SCREEN: RGB = (30, 40, 60)
STATE_BAR: dict[str, RGB] = {"ok": (20, 170, 60), "busy": (230, 160, 0),
                             "bad": (220, 30, 30), "gone": (130, 130, 136)}
STILL_PATTERNS = ("off", "on")
SCREEN_Z = 0.45  # the screen's centre over the master's
MASTER_W = 2.6  # as wide as the FastCAT coupler: the longest DC state fits its screen
SCREEN_SHARE = 0.92  # of the master's width
# The screen's texts (screen labels: one size on screen) at the whole line's camera, the
# widest view, where they must fit the screen.
SCREEN_SCALE = 0.62
# In a scenario's focused view they grow with the zoom up to this share of a scene unit an em
# (sized when "SYNCHRONIZING", 9.3 em, was the widest line; now "waiting start time", 8.7
# em, and "no slave answers", 8.5 em, fill most of the screen): ~14 px an em in a
# focus on the master at 1280 x 720. At 0.62 everywhere they were ~7 px in dc_sync_lost's
# three focused pictures, too small to read.
SCREEN_EM = 0.24
# The largest scale drawn from the 16 px glyph atlas, which app/ui/glyphs.py warms (a larger
# one would pack its glyphs in a new atlas in whatever order the page meets them).
MAX_SCREEN_SCALE = 1.3
ESM_Z = -0.9  # the drive's ESM state: under its LEDs, above the cable coming in
# The drive's alarm under its ESM state: the number its display shows (seed 004 ch. 5
# "Gli allarmi vengono visualizzati sia sul display del drive"), between the cable ports.
ALARM_Z = -1.55
# A slave's LED rows from the top down: the drive's four (seed 004 ch. 5: an L/A per port,
# Status, Error) between the "EtherCAT" label and the ESM state.
LED_TOP_Z, LED_STEP_Z = 0.85, 0.42


def wrap(text: str, width: int) -> str:
    """``text`` on lines of at most ``width`` characters where it allows, broken after a
    space, an underscore or a hyphen; the underscore or hyphen stays at the end of its line,
    so "4AI-" / "U-I" still spells the seed's 4AI-U-I. A longer piece keeps a line of its
    own."""
    lines: list[str] = []
    line = ""
    for piece in re.findall(r"[^ _-]+[ _-]*|[ _-]+", text):
        if line and len((line + piece).rstrip()) > width:
            lines.append(line.rstrip())
            line = piece
        else:
            line += piece
    return "\n".join([*lines, line.rstrip()])


def screen_scale(px_per_unit: float) -> float:
    """The scale of the master's screen texts where the screen shows at ``px_per_unit``:
    SCREEN_EM scene units an em, never below the whole line's size nor above the warmed
    atlas."""
    return round(min(MAX_SCREEN_SCALE, max(SCREEN_SCALE, SCREEN_EM * px_per_unit / EM_PX)), 2)


def led_colour(name: str) -> str:
    """The colour of a slave LED from its name (ETG.1300: RUN green, ERR red)."""
    return "red" if "err" in name.lower() else "green"


def blink_words(leds: Iterable[tuple[str, str]]) -> str:
    """``[("LINK-ACT IN", "flickering"), ("LINK-ACT OUT", "flickering")]`` ->
    ``"LINK-ACT IN, LINK-ACT OUT flickering"``: only what a still picture cannot show."""
    by_pattern: dict[str, list[str]] = {}
    for name, pattern in leds:
        if pattern not in STILL_PATTERNS:
            by_pattern.setdefault(pattern, []).append(name)
    return "\n".join(f"{', '.join(names)} {PATTERN_WORDS.get(p, p)}"
                     for p, names in by_pattern.items())


def state_tone(entry: Mapping[str, Any], target: str | None = None) -> str:
    """ok / busy / bad / gone for a slave entry of the master snapshot; ok only in the
    master's target state (a slave the master parked in SAFEOP is not ok)."""
    if not entry or entry.get("present") is False or entry.get("state") is None:
        return "gone"
    if int(entry.get("al_status", 0)) & AL_STATUS_ERROR_FLAG or entry.get("al_status_code"):
        return "bad"
    wanted = target or entry.get("requested") or entry.get("state")
    return "ok" if entry.get("state") == wanted else "busy"


def header_text(entry: Mapping[str, Any], position: int) -> str:
    """``1 · 1002 · OP``, with the AL status code when there is one: what the master reads
    (a slave it lost is "not seen"; why is the instructor's, docs/ethercat-master.md)."""
    address = entry.get("station_address", "?")
    state = entry.get("state") or "not seen"
    text = f"{entry.get('position', position)} · {address} · {state}"
    code = int(entry.get("al_status_code") or 0)
    if code:
        text += f" · AL 0x{code:04X}"
    return text


class Body:
    """One device of the line: its nodes, header, state bar and legend."""

    width = 1.8
    title = ""

    def __init__(self, server: viser.ViserServer, device_id: str, x0: float, z0: float) -> None:
        self.device_id = device_id
        self.x0, self.z0 = x0, z0
        self.paint = Painter(server, f"/line/{device_id}")
        self.clickables: list[Any] = []
        self._bar: viser.BoxHandle | None = None
        self._tone = ""

    @property
    def cx(self) -> float:
        return self.x0 + self.width / 2

    def at(self, dx: float, dz: float, y: float = FRONT_Y) -> tuple[float, float, float]:
        return (self.x0 + dx, y, self.z0 + dz)

    def build(self) -> None:
        """The body and its frame (bar, header, legend); subclasses add their front."""
        body = self.paint.box("body", (self.width * 0.96, BODY_D, BODY_H),
                              (self.cx, 0.0, self.z0), BODY)
        self.clickables.append(body)
        self.build_frame()
        if self.title:
            self.paint.label("title", self.title, self.at(self.width / 2, 1.72),
                             anchor="center-center", scale=0.85)

    def build_frame(self, legend: bool = True) -> None:
        top = self.z0 + BODY_H / 2
        self._bar = self.paint.box("state_bar", (self.width * 0.96, BODY_D * 0.9, 0.16),
                                   (self.cx, 0.0, top + 0.1), STATE_BAR["gone"])
        self.paint.label("header", "", (self.cx, FRONT_Y, top + 0.26), anchor="bottom-center",
                         scale=0.72)
        if legend:
            self.paint.label("legend", "", (self.cx, FRONT_Y, self.z0 - BODY_H / 2 - 0.15),
                             anchor="top-center", scale=0.62)

    def update_frame(self, entry: Mapping[str, Any], position: int, legend: str,
                     target: str | None = None) -> None:
        self.show_frame(state_tone(entry, target), header_text(entry, position), legend)

    def show_frame(self, tone: str, header: str, legend: str) -> None:
        """Bar colour, header and legend, each sent only when it differs from what the browsers
        have: any scene message makes every browser redraw its 3D canvas (issue 7)."""
        if tone != self._tone and self._bar is not None:
            self._bar.color = STATE_BAR[tone]
            self._tone = tone
        self.paint.set_text("header", header)
        self.paint.set_text("legend", legend)

    def update(self, snap: Mapping[str, Any], t_us: int) -> str:
        """Bring the front to ``snap``; returns the LED legend."""
        return ""

    def port(self, side: str) -> tuple[float, float]:
        """(x, z) where a cable enters (``in``, left) or leaves (``out``, right)."""
        return (self.x0 - 0.05 if side == "in" else self.x0 + self.width + 0.05,
                self.z0 - BODY_H / 2 + 0.5)


def as_drawn(devices: Mapping[str, Any], device: str) -> Mapping[str, Any]:
    """A slave's snapshot as the line shows it: a drive's EtherCAT side carries its drive's
    network LEDs (the drive owns them, devices/servo/leds.py; the slave only drives them) and
    the alarm its display shows (``drive_alarm``, the drive's ``alarm`` or None)."""
    snap = devices.get(device) or {}
    drive = snap.get("drive")
    if drive is None or "leds" in snap:
        return snap
    own = devices.get(drive) or {}
    return {**snap, "leds": own.get("leds") or {}, "drive_alarm": own.get("alarm")}


def alarm_words(alarm: Mapping[str, Any] | None) -> str:
    """``alarm 34``: the number the drive's display shows in alarm (seed 004 ch. 5, its
    alarm table's numbers), "" without one. The name stays with the Drive tab and the Codes
    tab: "alarm 34 SYNC_TIMEOUT" is wider than the drive's body."""
    return f"alarm {alarm['code']}" if alarm else ""


class SlaveBody(Body):
    """Any EtherCAT slave with ``leds`` in its snapshot: the drive's CoE side, or a kind the
    dashboard does not draw in detail. LEDs in snapshot order, red for the error LED."""

    def __init__(self, server: viser.ViserServer, device_id: str, x0: float, z0: float,
                 snap: Mapping[str, Any]) -> None:
        super().__init__(server, device_id, x0, z0)
        self.title = str(snap.get("drive") or device_id)
        self._led_names = [str(n) for n in (snap.get("leds") or {})]

    def build(self) -> None:
        super().build()
        self.paint.label("bus", "EtherCAT", self.at(self.width / 2, 1.3),
                         anchor="center-center", scale=0.62)
        for i, name in enumerate(self._led_names):
            z = LED_TOP_Z - i * LED_STEP_Z
            self.paint.led(name, self.at(0.3, z))
            self.paint.label(f"name_{i}", name, self.at(0.52, z), scale=0.65)
        # Two lines ("ESM" over the state): "ESM SAFEOP" on one is wider than the body.
        self.paint.label("esm", "", self.at(self.width / 2, ESM_Z), anchor="center-center",
                         scale=0.7)
        # Hidden without an alarm: an empty label still draws its background, a speck.
        self.paint.label("alarm", "", self.at(self.width / 2, ALARM_Z),
                         anchor="center-center", scale=0.7).visible = False

    def update(self, snap: Mapping[str, Any], t_us: int) -> str:
        leds = snap.get("leds") or {}
        for name in self._led_names:
            self.paint.set_led(name, led_colour(name), str(leds.get(name, "off")), t_us)
        self.paint.set_text("esm", f"ESM\n{snap.get('esm', '-')}")
        alarm = alarm_words(snap.get("drive_alarm"))
        self.paint.set_text("alarm", alarm)
        label = self.paint.labels["alarm"]
        if label.visible is not bool(alarm):
            label.visible = bool(alarm)
        return blink_words((n, str(leds.get(n, "off"))) for n in self._led_names)


class MasterBody(Body):
    """The master: a PC with a screen showing its start-up phase and the DC state."""

    title = "Master"
    width = MASTER_W

    def __init__(self, server: viser.ViserServer, x0: float, z0: float) -> None:
        super().__init__(server, "master", x0, z0)

    def build(self) -> None:
        super().build()
        screen = self.paint.box("screen", (self.width * SCREEN_SHARE, 0.1, 1.5),
                                (self.cx, FRONT_Y + 0.02, self.z0 + SCREEN_Z), SCREEN)
        self.clickables.append(screen)
        self.paint.label("phase", "", self.at(self.width / 2, 0.8), anchor="center-center",
                         scale=SCREEN_SCALE)
        # Two lines from the top down ("DC" / "not synchronized"), inside the screen.
        self.paint.label("dc", "", self.at(self.width / 2, 0.5), anchor="top-center",
                         scale=SCREEN_SCALE)
        self.paint.led("link", self.at(0.3, -0.9))
        self.paint.label("link_name", "link", self.at(0.52, -0.9), scale=0.65)

    @property
    def screen_centre(self) -> tuple[float, float, float]:
        return self.at(self.width / 2, SCREEN_Z)

    def zoom(self, px_per_unit: float | None) -> None:
        """The screen's texts for a view showing the screen at ``px_per_unit`` (a scenario's
        focus, which every browser shares), or for any view (None: the whole line's size)."""
        scale = SCREEN_SCALE if px_per_unit is None else screen_scale(px_per_unit)
        for key in ("phase", "dc"):
            label = self.paint.labels[key]
            if label.font_screen_scale != scale:
                label.font_screen_scale = scale

    def update(self, snap: Mapping[str, Any], t_us: int) -> str:
        phase = str(snap.get("phase", "running" if snap.get("slaves") else "-"))
        note = snap.get("phase_note_short")  # "2 lost, 1 held": the panel has it in full
        self.paint.set_text("phase", f"{phase_text(phase)}\n{note}" if note else
                            phase_text(phase))
        dc = snap.get("dc") or {}
        self.paint.set_text("dc", f"DC\n{dc_words(str(dc.get('state', '-')))}")
        link = snap.get("link", True)
        self.paint.set_led("link", "green", "on" if link else "off", t_us)
        return "external master" if snap.get("external") else ""

    def update_master_frame(self, snap: Mapping[str, Any], legend: str = "") -> None:
        """The master's own frame: the bar red out of sync (NOT_SYNCHRONIZED: what the
        master measures, not the injected DC fault) or on a lost link, amber while starting
        or while slaves are lost or held in SAFEOP (the phase's note);
        the header names the target state; ``legend`` is :meth:`update`'s."""
        dc = snap.get("dc") or {}
        phase = snap.get("phase", "running")
        bad = dc.get("state") == "NOT_SYNCHRONIZED" or not snap.get("link", True)
        running = phase == "running" and not snap.get("phase_note")
        entry = {"state": "running" if running else phase,
                 "requested": "running", "al_status_code": 1 if bad else 0}
        # One text per label per frame: the slave header and then "target ..." made the
        # label change twice in every frame, so every browser got it 30 times a second.
        self.show_frame(state_tone(entry), f"target {snap.get('target', '-')}", legend)


class RailFrame(Body):
    """The FastCAT rail's frame in the line (bar and header); the rail itself, its LED words
    and its legend are ``app.ui.rail_scene``'s."""

    def __init__(self, server: viser.ViserServer, device_id: str, x0: float, z0: float,
                 width: float) -> None:
        super().__init__(server, device_id, x0, z0)
        self.width = width

    def build(self) -> None:
        self.build_frame(legend=False)
        if self._bar is not None:
            self.clickables.append(self._bar)
