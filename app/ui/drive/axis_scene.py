"""The 3D servo axis under the DIN rail: drive, motor, screw, carriage, switches.

Same conventions as the rail (``app.ui.rail_scene``): z up, the front faces -y, the camera on
-y. Left to right: the drive with its 7-segment display (seed 004: "Fr" when disabled, dashes
while saving, the alarm code in alarm) and its network LEDs (ch. 5: L/A IN, Status, L/A OUT,
Error; drawn only on EtherCAT: ``BUS_LEDS``), the motor with a nib on its coupling that
turns with the shaft, the screw, and the carriage at ``axis.carriage`` between the negative
limit switch, the home switch and the positive limit switch at the positions the rig file
sets. A switch lights while the carriage (or a forced input) actuates it. Nodes are built
once; per frame only positions, colours, texts and visibilities that changed are sent.

Labels keep one size on screen whatever the zoom (viser "screen" labels), so the layout keeps
them apart by placing, not by measuring: the caption (position, velocity, actuated switches)
sits in the empty band above the travel, beside the drive's name; the switch labels hang
under the bed, each on the side of its switch away from its nearer neighbour (the default
rig's home switch is a few pixels from NL); the motor's label under the motor, clear of the
carriage's at the end stop. tests/app/test_axis_labels.py checks them at the default camera.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import viser

from app.ui.rail_scene import LED_OFF, LED_SIZE, PATTERN_WORDS, led_color
from devices.servo.leds import BUS_LEDS, ERROR, LINK_IN, LINK_OUT, STATUS

RGB = tuple[int, int, int]

AXIS_TOP = 1.9  # extent of one axis block above / below its baseline z
AXIS_BOTTOM = -1.35
AXIS_HEIGHT = AXIS_TOP - AXIS_BOTTOM
AXIS_SPACING = AXIS_HEIGHT + 0.5  # several drives stack downwards
DRIVE_W, DRIVE_H, DRIVE_D = 1.7, 2.9, 1.6
DRIVE_X = DRIVE_W / 2 + 0.05
DISPLAY_Z = 1.08  # the 7-segment display's centre: above the four network LEDs
MOTOR_X0, MOTOR_W = 2.1, 1.0
TRAVEL_X0 = MOTOR_X0 + MOTOR_W + 0.35  # scene x of the first user unit shown
TRAVEL_MARGIN = 0.04  # share of the switch span shown beyond each limit switch
FRONT = -0.55  # front plane of the axis parts (the drive's front is -DRIVE_D / 2)

DRIVE_BODY: RGB = (214, 219, 228)
DISPLAY_BG: RGB = (22, 22, 24)
SEGMENT_ON: RGB = (255, 45, 30)
SEGMENT_OFF: RGB = (58, 26, 26)
MOTOR: RGB = (70, 72, 80)
SCREW: RGB = (150, 152, 160)
BED: RGB = (188, 190, 196)
CARRIAGE: RGB = (31, 79, 143)
CARRIAGE_JAMMED: RGB = (170, 40, 40)
CARRIAGE_SIZE = (0.7, 1.0, 0.8)
LEGEND_ANCHOR, LEGEND_SCALE = "top-left", 0.75
SWITCH_OFF: RGB = (90, 92, 98)
SWITCH_LIT: dict[str, RGB] = {"neg": (235, 25, 25), "pos": (235, 25, 25),
                              "home": (255, 196, 0)}
NIB: RGB = (255, 196, 0)
HOME_CAM: RGB = (236, 222, 170)
BUS_SHORT = {"modbus": "Modbus", "canopen": "CANopen", "ethercat": "EtherCAT",
             "profinet": "Profinet"}

# 7-segment patterns (a top, b upper right, c lower right, d bottom, e lower left, f upper
# left, g middle) for what the display shows: digits, "Fr", "En", "--".
SEGMENTS: dict[str, str] = {
    "0": "abcdef", "1": "bc", "2": "abdeg", "3": "abcdg", "4": "bcfg", "5": "acdfg",
    "6": "acdefg", "7": "abc", "8": "abcdefg", "9": "abcdfg", "-": "g", " ": "",
    "F": "aefg", "r": "eg", "E": "adefg", "n": "ceg", "A": "abcefg", "L": "def", "H": "bcefg",
    "P": "abefg", "o": "cdeg", "d": "bcdeg", "b": "cdefg", "C": "adef", "U": "bcdef",
    "t": "defg", "u": "cde", "S": "acdfg",
}
DIGITS = 2
SEG_W, SEG_H, SEG_T = 0.26, 0.44, 0.055
# Segment centre (dx, dz) in a digit and whether it is horizontal.
SEGMENT_PLACES: dict[str, tuple[float, float, bool]] = {
    "a": (0.0, SEG_H / 2, True), "g": (0.0, 0.0, True), "d": (0.0, -SEG_H / 2, True),
    "f": (-SEG_W / 2, SEG_H / 4, False), "b": (SEG_W / 2, SEG_H / 4, False),
    "e": (-SEG_W / 2, -SEG_H / 4, False), "c": (SEG_W / 2, -SEG_H / 4, False),
}
# The drive's network LEDs (ch. 5 "Connessioni e Leds Drive EtherCAT"): name, colour, z, in
# the front's order "L/A Status L/A Error" (IN port: L/A, Status; OUT port: L/A, Error).
# 0.35 apart: their labels (one line each) do not overlap at the default camera, and the
# lowest (its label runs past the drive) stays above the motor's label.
LED_LABEL_SCALE = 0.6  # four rows between the display and the motor's label
NETWORK_LEDS: tuple[tuple[str, str, float], ...] = (
    (LINK_IN, "green", 0.6), (STATUS, "green", 0.25), (LINK_OUT, "green", -0.1),
    (ERROR, "red", -0.45))
# The axis switches (seed 004 ch. 2, CN2 inputs: pin 8 Negative limit switch, pin 9 Positive
# limit switch, pin 14 Home switch): key, the axis field with its position, the label.
SWITCHES: tuple[tuple[str, str, str], ...] = (
    ("neg", "neg_limit", "NL"), ("home", "home_switch", "home"), ("pos", "pos_limit", "PL"))
SWITCH_LABEL_Z = -0.82  # top of the switch labels, under the bed
CARRIAGE_LABEL_Z = 0.5  # bottom of the carriage's position, over the carriage
MOTOR_LABEL_Z = -0.62  # top of the motor's label, under the motor
LEGEND_Z = AXIS_TOP - 0.08  # top of the two-line caption, above the travel


def switch_label_anchors(xs: Mapping[str, float]) -> dict[str, str]:
    """The anchor of each switch label, ``xs`` being the switches' scene x: the leftmost label
    ends at its switch, the rightmost starts at it, the middle one opens toward the wider gap.
    Two labels then grow away from each other however close their switches are (the home
    switch on a limit switch included), and the middle one has at least half the span."""
    order = sorted(xs, key=lambda k: (xs[k], [s[0] for s in SWITCHES].index(k)))
    first, mid, last = order
    toward_right = xs[last] - xs[mid] >= xs[mid] - xs[first]
    return {first: "top-right", mid: "top-left" if toward_right else "top-right",
            last: "top-left"}


def display_segments(text: str) -> list[str]:
    """The lit segments of each digit, right-aligned as the drive shows " 9" or "16"; a
    character the display cannot draw shows as a dash."""
    shown = (text or "")[-DIGITS:].rjust(DIGITS)
    return [SEGMENTS.get(ch, SEGMENTS.get(ch.upper(), "g")) for ch in shown]


@dataclass(frozen=True)
class Travel:
    """Maps user units of the axis (the rig file's switch positions) onto scene x."""

    low: float
    high: float
    x0: float
    x1: float

    @classmethod
    def of(cls, axis: Mapping[str, Any], length: float) -> Travel:
        points = [float(axis.get(k, 0.0)) for k in ("neg_limit", "pos_limit", "home_switch")]
        low, high = min(points), max(points)
        span = max(high - low, 1.0)
        return cls(low - span * TRAVEL_MARGIN, high + span * TRAVEL_MARGIN, TRAVEL_X0,
                   max(length - 0.3, TRAVEL_X0 + 1.0))

    def x(self, position: float) -> float:
        """Scene x of an axis position, clamped to the drawn travel (the end stops)."""
        share = (position - self.low) / (self.high - self.low)
        return self.x0 + min(max(share, 0.0), 1.0) * (self.x1 - self.x0)


class AxisScene:
    """Scene nodes of one drive's axis under ``/<drive_id>_axis``; server-level."""

    def __init__(self, server: viser.ViserServer, drive_id: str, z: float,
                 length: float, causes: bool = True) -> None:
        self._server = server
        # The shared scene: with trainees (causes=False) it shows no injected cause, neither
        # the caption's "load jammed" nor the red carriage; an instructor's page draws them
        # over it (axis_jam.py).
        self.causes = causes
        self._root = f"/{drive_id}_axis"
        self.z = z
        self.length = length
        self._travel: Travel | None = None
        self._sent: dict[str, Any] = {}  # last value sent per node property
        self._segments: list[dict[str, viser.BoxHandle]] = []
        self._leds: dict[str, tuple[viser.BoxHandle, viser.LabelHandle, str]] = {}
        self._leds_for: tuple[str, ...] | None = None  # the LEDs built, by fieldbus
        self._switches: dict[str, tuple[viser.BoxHandle, viser.LabelHandle]] = {}
        self._labels: list[viser.LabelHandle] = []
        self._build_static()

    def _at(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        return (x, y, z + self.z)

    def _label(self, name: str, text: str, x: float, y: float, z: float, anchor: Any,
               scale: float) -> viser.LabelHandle:
        label = self._server.scene.add_label(f"{self._root}/{name}", text,
                                             position=self._at(x, y, z), anchor=anchor,
                                             font_screen_scale=scale)
        self._labels.append(label)
        return label

    # ---- building ---------------------------------------------------------------------
    def _build_static(self) -> None:
        scene, at, root = self._server.scene, self._at, self._root
        front = -DRIVE_D / 2 - 0.04
        scene.add_box(f"{root}/drive", color=DRIVE_BODY, dimensions=(DRIVE_W, DRIVE_D, DRIVE_H),
                      position=at(DRIVE_X, 0.0, AXIS_TOP - DRIVE_H / 2))
        self._name = self._label("drive_name", "", DRIVE_X, front, 1.62, "center-center", 0.8)
        scene.add_box(f"{root}/display", color=DISPLAY_BG, dimensions=(1.0, 0.05, 0.66),
                      position=at(DRIVE_X, front, DISPLAY_Z))
        for digit in range(DIGITS):
            cx = DRIVE_X + (digit - (DIGITS - 1) / 2) * 0.4
            boxes = {}
            for seg, (dx, dz, horizontal) in SEGMENT_PLACES.items():
                dims = (SEG_W - SEG_T, 0.03, SEG_T) if horizontal else \
                    (SEG_T, 0.03, SEG_H / 2 - SEG_T)
                boxes[seg] = scene.add_box(f"{root}/seg{digit}{seg}", color=SEGMENT_OFF,
                                           dimensions=dims, position=at(cx + dx, front - 0.03,
                                                                        DISPLAY_Z + dz))
            self._segments.append(boxes)
        # Motor, coupling, screw and bed.
        mz = 0.0
        scene.add_box(f"{root}/motor", color=MOTOR, dimensions=(MOTOR_W, 1.0, 1.0),
                      position=at(MOTOR_X0 + MOTOR_W / 2, 0.0, mz))
        self._label("motor_label", "motor", MOTOR_X0 + MOTOR_W / 2, FRONT - 0.1,
                    MOTOR_LABEL_Z, "top-center", 0.7)
        along_x = (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0)
        coupling_x = MOTOR_X0 + MOTOR_W + 0.1
        scene.add_cylinder(f"{root}/coupling", radius=0.22, height=0.2, color=MOTOR,
                           wxyz=along_x, position=at(coupling_x, 0.0, mz))
        self._nib = scene.add_box(f"{root}/nib", color=NIB, dimensions=(0.22, 0.1, 0.1),
                                  position=at(coupling_x, 0.0, mz + 0.17))
        self._nib_x = coupling_x
        screw_len = self.length - coupling_x
        scene.add_cylinder(f"{root}/screw", radius=0.08, height=screw_len, color=SCREW,
                           wxyz=along_x, position=at(coupling_x + screw_len / 2, 0.0, mz))
        scene.add_box(f"{root}/bed", color=BED, dimensions=(screw_len, 1.1, 0.22),
                      position=at(coupling_x + screw_len / 2, 0.15, mz - 0.62))
        self._carriage = scene.add_box(f"{root}/carriage", color=CARRIAGE,
                                       dimensions=CARRIAGE_SIZE, position=at(TRAVEL_X0, 0.0,
                                                                             mz))
        self._carriage_label = self._label("carriage_label", "", TRAVEL_X0, FRONT,
                                           mz + CARRIAGE_LABEL_Z, "bottom-center", 0.8)
        self._legend = self._label("legend", "", TRAVEL_X0, FRONT, LEGEND_Z, LEGEND_ANCHOR,
                                   LEGEND_SCALE)

    def _build_leds(self, names: tuple[str, ...]) -> None:
        """The network LEDs ``names`` (those of the drive's fieldbus), the others removed:
        built anew when the fieldbus changes, rather than hidden, so that nothing else that
        shows or hides labels (a focused view, app/ui/line/focus_labels.py) brings them back."""
        for box, label, _colour in self._leds.values():
            box.remove()
            label.remove()
        self._leds = {}
        self._sent = {k: v for k, v in self._sent.items() if not k.startswith("led_")}
        front = -DRIVE_D / 2 - 0.04
        for name, colour, z in NETWORK_LEDS:
            if name not in names:
                continue
            key = name.replace("/", "").replace(" ", "_")
            box = self._server.scene.add_box(f"{self._root}/led_{key}", color=LED_OFF,
                                             dimensions=LED_SIZE,
                                             position=self._at(0.4, front, z))
            label = self._server.scene.add_label(
                f"{self._root}/led_{key}_label", f"{name} off",
                position=self._at(0.7, front, z), anchor="center-left",
                font_screen_scale=LED_LABEL_SCALE)
            self._leds[name] = (box, label, colour)

    def _build_switches(self, travel: Travel, axis: Mapping[str, Any]) -> None:
        scene, at = self._server.scene, self._at
        # The home switch is actuated from its position upwards (a cam along the positive
        # side, DSP 402 pictures of methods 3 / 4 / 19 / 20): drawn as a strip to the end.
        home = travel.x(float(axis.get("home_switch", 0.0)))
        scene.add_box(f"{self._root}/home_cam", color=HOME_CAM,
                      dimensions=(travel.x1 - home, 0.04, 0.1),
                      position=at((home + travel.x1) / 2, FRONT + 0.04, -0.5))
        xs = {key: travel.x(float(axis.get(field, 0.0))) for key, field, _ in SWITCHES}
        anchors = switch_label_anchors(xs)
        for key, _, text in SWITCHES:
            box = scene.add_box(f"{self._root}/switch_{key}", color=SWITCH_OFF,
                                dimensions=(0.16, 0.5, 0.3),
                                position=at(xs[key], FRONT + 0.1, -0.62))
            label = self._label(f"switch_{key}_label", text, xs[key], FRONT, SWITCH_LABEL_Z,
                                anchors[key], 0.7)
            self._switches[key] = (box, label)

    # ---- per frame ----------------------------------------------------------------------
    def _send(self, key: str, node: Any, attr: str, value: Any) -> None:
        if self._sent.get(key) != value:
            setattr(node, attr, value)
            self._sent[key] = value

    def update(self, drive_id: str, snap: Mapping[str, Any], t_us: int) -> None:
        """Bring the axis to the drive snapshot ``snap`` at simulated time ``t_us`` (its
        ``leds``: the network LEDs, which its EtherCAT slave drives)."""
        axis = snap.get("axis") or {}
        if self._travel is None:
            self._travel = Travel.of(axis, self.length)
            self._build_switches(self._travel, axis)
        travel = self._travel
        carriage = float(axis.get("carriage", 0.0))
        x = round(travel.x(carriage), 3)
        self._send("carriage", self._carriage, "position", self._at(x, 0.0, 0.0))
        self._send("carriage_label_pos", self._carriage_label, "position",
                   self._at(x, FRONT, CARRIAGE_LABEL_Z))
        self._send("carriage_label", self._carriage_label, "text",
                   f"{snap.get('position_counts', 0)}")
        self._send("carriage_color", self._carriage, "color",
                   CARRIAGE_JAMMED if self.causes and snap.get("jammed") else CARRIAGE)
        # The nib turns with the motor shaft: one turn per motor revolution.
        angle = 2 * math.pi * (float(axis.get("motor_turns", 0.0)) % 1.0)
        nib = (round(0.17 * math.sin(angle), 3), round(0.17 * math.cos(angle), 3))
        self._send("nib", self._nib, "position", self._at(self._nib_x, -nib[0], nib[1]))
        limits = snap.get("limits") or {}
        for key, (box, _label) in self._switches.items():
            lit = bool(limits.get(key))
            self._send(f"switch_{key}", box, "color", SWITCH_LIT[key] if lit else SWITCH_OFF)
        self._update_drive(drive_id, snap, t_us)
        self._send("legend", self._legend, "text", legend_label(snap, self.causes))

    def _update_drive(self, drive_id: str, snap: Mapping[str, Any], t_us: int) -> None:
        bus = BUS_SHORT.get(str(snap.get("fieldbus", "")), str(snap.get("fieldbus", "")))
        self._send("name", self._name, "text", f"{drive_id} · {bus} {snap.get('node_id', '')}")
        lit = display_segments(str(snap.get("display", "")) if snap.get("powered") else "")
        for digit, boxes in enumerate(self._segments):
            for seg, box in boxes.items():
                colour = SEGMENT_ON if seg in lit[digit] else SEGMENT_OFF
                self._send(f"seg{digit}{seg}", box, "color", colour)
        leds = snap.get("leds") or {}
        # Only the LEDs the drive's fieldbus has (seed 004 prints them for EtherCAT alone):
        # four dark LEDs on a Modbus drive read as a dead network.
        has = BUS_LEDS.get(str(snap.get("fieldbus", "")), ())
        if self._leds_for != has:
            self._build_leds(has)
            self._leds_for = has
        for name, (box, label, colour) in self._leds.items():
            pattern = str(leds.get(name, "off"))
            self._send(f"led_{name}", box, "color", led_color(colour, pattern, t_us))
            self._send(f"led_{name}_text", label, "text",
                       f"{name} {PATTERN_WORDS.get(pattern, pattern)}")

    def network_leds_shown(self) -> list[str]:
        """The network LEDs drawn now, top down (tests)."""
        return list(self._leds)

    def segment_colors(self) -> list[dict[str, RGB]]:
        """The colour each display segment shows now (tests)."""
        return [{seg: self._sent.get(f"seg{d}{seg}", SEGMENT_OFF) for seg in SEGMENT_PLACES}
                for d in range(DIGITS)]

    def labels(self) -> list[viser.LabelHandle]:
        """Every label of the axis (tests: that none covers another)."""
        return [*self._labels, *(label for _box, label, _c in self._leds.values())]

    @property
    def root(self) -> str:
        return self._root

    def carriage_at(self) -> tuple[float, float, float]:
        """Where the carriage is drawn now (scene coordinates)."""
        return tuple(self._carriage.position)  # type: ignore[return-value]

    def legend_at(self) -> tuple[float, float, float]:
        return tuple(self._legend.position)  # type: ignore[return-value]

    def carriage_x(self) -> float:
        """Scene x of the carriage now (tests)."""
        position = self._sent.get("carriage")
        return float(position[0]) if position else TRAVEL_X0


def legend_parts(snap: Mapping[str, Any], causes: bool = True) -> list[str]:
    """The axis in words: what a still picture cannot show by itself; ``causes=False`` (a
    rig with trainees) leaves out the injected jam (docs/classroom.md)."""
    velocity = float(snap.get("velocity", 0.0))
    limits = snap.get("limits") or {}
    hit = [name for key, _, name in SWITCHES if limits.get(key)]
    parts = [f"position {snap.get('position_counts', 0)}", f"velocity {velocity:.0f} u/s",
             f"switches: {', '.join(hit) if hit else 'none'}"]
    if causes and snap.get("jammed"):
        parts.append("load jammed")
    return parts


def legend_text(snap: Mapping[str, Any]) -> str:
    """The caption on one line: "position 0 · velocity 0 u/s · switches: home"."""
    return " · ".join(legend_parts(snap))


def legend_label(snap: Mapping[str, Any], causes: bool = True) -> str:
    """The caption as the scene shows it: the motion on the first line, the switches (and a
    jammed load) on the second, so that it stays within the travel's width."""
    parts = legend_parts(snap, causes)
    return " · ".join(parts[:2]) + "\n" + " · ".join(parts[2:])
