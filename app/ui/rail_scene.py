"""The 3D front view of a FastCAT DIN rail: coupler, modules in slot order, their LEDs.

Geometry is in "module widths" (one I/O module is 1.0 wide), z up, the front of the rail
facing -y, so the fixed camera sits on -y and looks along +y. The scene is built from the
snapshot's ``rail`` and rebuilt per slot only when what a slot *is* changes (type, plugged,
powered, detected type); every frame after that only touches LED colours that flip, so the
websocket carries a handful of colour messages per second, not the scene.

LEDs animate from the simulated time of the frame (``devices.leds.is_lit``), never wall time:
a paused runtime shows a frozen, reproducible picture.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import viser

from devices.leds import LedPattern, is_lit

logger = logging.getLogger(__name__)

MODULE_W = 1.0
COUPLER_W = 2.6
BODY_H = 4.2
BODY_D = 2.0
FRONT_Y = -BODY_D / 2
RAIL_H = 1.4
LED_SIZE = (0.42, 0.12, 0.24)

RGB = tuple[int, int, int]

LIT: dict[str, RGB] = {"red": (235, 25, 25), "yellow": (255, 196, 0), "green": (20, 200, 60)}
LED_OFF: RGB = (72, 72, 76)
BODY: RGB = (228, 230, 234)
BODY_UNPOWERED: RGB = (150, 152, 158)
COUPLER_BODY: RGB = (206, 214, 226)
RAIL: RGB = (168, 170, 176)
# The back plate behind each housing: the shade a housing's side face takes under the scene's
# light (BODY at ~0.79, a front face at ~0.93), so a seam looked at straight on reads as one
# looked at from the side.
SEAM: RGB = (192, 194, 198)
BACK_D = 0.1  # the plate's depth, flush with the housings' back
CNF_IDLE: RGB = (40, 70, 140)
CNF_PRESSED: RGB = (80, 160, 255)
SWITCH: RGB = (40, 40, 44)

# Coupler LEDs: (snapshot name, colour, z on the front face).
COUPLER_LEDS: tuple[tuple[str, str, float], ...] = (
    ("RUN", "green", 1.05), ("ERR", "red", 0.6), ("LINK", "green", 0.15))
MODULE_LEDS: tuple[tuple[str, str, float], ...] = (("red", "red", 0.45), ("yellow", "yellow", 0.0))


def slot_x(slot: int) -> float:
    """Centre x of module slot ``slot`` (1-based, the seed's module number)."""
    return COUPLER_W + (slot - 0.5) * MODULE_W


def rail_length(slots: int) -> float:
    return COUPLER_W + max(slots, 1) * MODULE_W


_PATTERNS = {p.value: p for p in LedPattern}  # a dict lookup: LedPattern(name) is slow


def led_lit(pattern: str, t_us: int) -> bool:
    """Whether an LED showing the pattern named ``pattern`` is lit at ``t_us``."""
    found = _PATTERNS.get(pattern)
    if found is None:  # an unknown pattern is a model bug; show it dark rather than crash
        logger.warning("unknown LED pattern %r", pattern)
        return False
    return is_lit(found, t_us)


def led_color(colour: str, pattern: str, t_us: int) -> RGB:
    return LIT[colour] if led_lit(pattern, t_us) else LED_OFF


PATTERN_WORDS = {"off": "off", "on": "on", "flickering": "flickering", "blinking": "blinking",
                 "single_flash": "single flash", "double_flash": "double flash",
                 "triple_flash": "triple flash"}


def slot_ranges(slots: list[int]) -> str:
    """``[1, 2, 3, 5]`` -> ``1-3, 5``."""
    runs: list[list[int]] = []
    for slot in sorted(slots):
        if runs and runs[-1][1] == slot - 1:
            runs[-1][1] = slot
        else:
            runs.append([slot, slot])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs)


def module_led_legend(leds: Mapping[str, str]) -> str:
    """What the module LEDs are doing, in words: a still picture cannot show a blink."""
    parts = []
    for colour in ("red", "yellow"):
        by_pattern: dict[str, list[int]] = {}
        for name, pattern in leds.items():
            slot, _, which = name.partition(".")
            if which == colour and slot.isdigit() and pattern != "off":
                by_pattern.setdefault(pattern, []).append(int(slot))
        for pattern, slots in sorted(by_pattern.items()):
            parts.append(f"{colour} {PATTERN_WORDS.get(pattern, pattern)}: "
                         f"{slot_ranges(slots)}")
    return "module LEDs (red above, yellow below): " + ("; ".join(parts) or "all off")


def shown_entry(entry: Mapping[str, Any], causes: bool) -> Mapping[str, Any]:
    """A slot as the shared scene draws it: with trainees (``causes=False``) a module's supply
    is a hidden cause (only the instructor switches it off, docs/classroom.md), so the module
    is drawn powered and a trainee reads what the real module shows, its LEDs dark."""
    if causes or entry.get("powered", True):
        return entry
    return {**entry, "powered": True}


def slot_shape(entry: Mapping[str, Any]) -> tuple[Any, ...]:
    """What a slot looks like apart from its LEDs; a change rebuilds the slot's nodes."""
    return (entry.get("type"), entry.get("plugged", True), entry.get("powered", True),
            entry.get("detected_as"), entry.get("module_number"))


@dataclass
class _SlotView:
    shape: tuple[Any, ...]
    nodes: list[viser.SceneNodeHandle] = field(default_factory=list)
    leds: dict[str, tuple[viser.BoxHandle, str]] = field(default_factory=dict)

    def remove(self) -> None:
        for node in self.nodes:
            node.remove()


class RailScene:
    """Scene nodes of one FastCAT under ``/<device_id>``; server-level, shared by all clients."""

    def __init__(self, server: viser.ViserServer, device_id: str, z: float = 0.0,
                 causes: bool = True) -> None:
        """``causes=False``: a rig with trainees, whose shared scene shows no module switched
        off (:func:`shown_entry`); each instructor connection draws those over it
        (app/ui/rail_power.py)."""
        self._server = server
        self._root = f"/{device_id}"
        self._causes = causes
        self.builds: dict[int, int] = {}  # how often each slot was (re)built: shadows redraw
        self._z = z  # several couplers stack their rails downwards
        self._slots: dict[int, _SlotView] = {}
        self._coupler_leds: dict[str, tuple[viser.BoxHandle, str]] = {}
        self._coupler_labels: dict[str, viser.LabelHandle] = {}
        self._texts: dict[str, str] = {}  # label texts last sent, by label key
        self._legend: viser.LabelHandle | None = None
        self._colors: dict[str, RGB] = {}
        self._rail: viser.BoxHandle | None = None
        self._rotary: viser.LabelHandle | None = None
        self._rotary_value: int | None = None
        self._cnf: viser.BoxHandle | None = None
        self._cnf_pressed = False
        self.slot_count = 0

    # ---- building ---------------------------------------------------------------------
    def _at(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        return (x, y, z + self._z)

    def build_coupler(self) -> None:
        scene, at, root = self._server.scene, self._at, f"{self._root}/coupler"
        cx = COUPLER_W / 2
        front = FRONT_Y - 0.06
        scene.add_box(f"{root}/body", color=COUPLER_BODY,
                      dimensions=(COUPLER_W * 0.96, BODY_D, BODY_H), position=at(cx, 0.0, 0.0))
        self._add_back(f"{root}/back", cx, COUPLER_W)
        scene.add_label(f"{root}/name", "FastCAT", position=at(cx, front, 1.7),
                        anchor="center-center", font_screen_scale=1.15)
        for name, colour, z in COUPLER_LEDS:
            box = scene.add_box(f"{root}/led_{name}", color=LED_OFF, dimensions=LED_SIZE,
                                position=at(cx - 0.85, front, z))
            self._coupler_leds[name] = (box, colour)
            self._coupler_labels[name] = scene.add_label(
                f"{root}/led_{name}_label", f"{name} off", position=at(cx - 0.5, front, z),
                anchor="center-left", font_screen_scale=0.8)
        scene.add_cylinder(f"{root}/rotary", radius=0.3, height=0.1, color=SWITCH,
                           wxyz=(0.7071068, 0.7071068, 0.0, 0.0),
                           position=at(cx - 0.8, front, -0.55))
        self._rotary = scene.add_label(f"{root}/rotary_label", "ADDR -",
                                       position=at(cx - 0.4, front, -0.55),
                                       anchor="center-left", font_screen_scale=0.8)
        self._cnf = scene.add_box(f"{root}/cnf", color=CNF_IDLE, dimensions=(0.5, 0.16, 0.32),
                                  position=at(cx - 0.8, front, -1.35))
        scene.add_label(f"{root}/cnf_label", "CNF", position=at(cx - 0.4, front, -1.35),
                        anchor="center-left", font_screen_scale=0.8)

    def _build_rail(self, slots: int) -> None:
        for node in (self._rail, self._legend):
            if node is not None:
                node.remove()
        length = rail_length(slots) + 0.8
        self._rail = self._server.scene.add_box(
            f"{self._root}/rail", color=RAIL, dimensions=(length, 0.3, RAIL_H),
            position=self._at(length / 2 - 0.4, BODY_D / 2 + 0.15, 0.0))
        self._legend = self._server.scene.add_label(
            f"{self._root}/legend", "", position=self._at(rail_length(slots) / 2, FRONT_Y,
                                                          -BODY_H / 2 - 0.45),
            anchor="top-center", font_screen_scale=0.75)
        self._texts.pop("legend", None)

    def _build_slot(self, entry: Mapping[str, Any]) -> _SlotView:
        scene, at = self._server.scene, self._at
        slot = int(entry["slot"])
        x = slot_x(slot)
        base = f"{self._root}/slot{slot:02d}"
        view = _SlotView(shape=slot_shape(entry))
        module_type = entry.get("type")
        front = FRONT_Y - 0.06

        def label(name: str, text: str, z: float, scale: float) -> None:
            view.nodes.append(scene.add_label(f"{base}/{name}", text, position=at(x, front, z),
                                              anchor="center-center", font_screen_scale=scale))

        label("number", str(slot), 1.75, 0.9)
        if module_type is None:
            view.nodes.append(scene.add_box(
                f"{base}/body", color=BODY, dimensions=(MODULE_W * 0.92, 0.05, BODY_H * 0.9),
                position=at(x, BODY_D / 2 - 0.05, 0.0), opacity=0.25))
            label("type", "empty", 1.2, 0.75)
            return view
        plugged = bool(entry.get("plugged", True))
        pulled = 0.0 if plugged else -0.6  # an unplugged module hangs in front of its slot
        view.nodes.append(self.add_body(scene, entry))
        if plugged:  # a pulled module's slot stays see-through, as an empty one
            view.nodes.append(self._add_back(f"{base}/back", x, MODULE_W))
        label("type", str(module_type), 1.2, 0.75)
        for name, colour, z in MODULE_LEDS:
            key = f"{slot}.{name}"
            box = scene.add_box(f"{base}/led_{name}", color=LED_OFF, dimensions=LED_SIZE,
                                position=at(x, front + pulled, z))
            view.nodes.append(box)
            view.leds[key] = (box, colour)
            self._colors.pop(key, None)
        note = slot_note(entry)
        if note:
            view.nodes.append(self.add_note(scene, slot, note))
        return view

    def _add_back(self, name: str, x: float, width: float) -> viser.BoxHandle:
        """A plate the full width of a slot behind its housing: the housings are narrower
        than their slots, and where the camera looked straight along a seam (the middle of a
        long rail) it showed the background over and under the DIN rail, a broken line
        unlike the other seams (tests/app/test_rail_seams.py)."""
        return self._server.scene.add_box(
            name, color=SEAM, dimensions=(width, BACK_D, BODY_H),
            position=self._at(x, BODY_D / 2 - BACK_D / 2, 0.0))

    def add_body(self, scene: Any, entry: Mapping[str, Any]) -> viser.BoxHandle:
        """A module's body in ``scene`` (the server's, or an instructor connection's under the
        same name); greyed without supply, hanging in front of its slot when unplugged."""
        slot, plugged = int(entry["slot"]), bool(entry.get("plugged", True))
        powered = bool(entry.get("powered", True))
        return scene.add_box(
            f"{self._root}/slot{slot:02d}/body", color=BODY if powered else BODY_UNPOWERED,
            dimensions=(MODULE_W * 0.92, BODY_D, BODY_H),
            position=self._at(slot_x(slot), 0.0 if plugged else -0.6, 0.0),
            opacity=None if plugged else 0.35)

    def add_note(self, scene: Any, slot: int, note: str) -> viser.LabelHandle:
        """The note under a module ("power off", "seen DI16") in ``scene``."""
        return scene.add_label(f"{self._root}/slot{slot:02d}/note", note,
                               position=self._at(slot_x(slot), FRONT_Y - 0.06, -1.0),
                               anchor="center-center", font_screen_scale=0.7)

    # ---- per frame ----------------------------------------------------------------------
    def update(self, snap: Mapping[str, Any], t_us: int) -> bool:
        """Bring the scene to ``snap`` at simulated time ``t_us``; True when the rail was
        rebuilt in length (the caller re-frames the camera)."""
        rail = snap.get("rail") or []
        resized = len(rail) != self.slot_count
        if resized:
            self._build_rail(len(rail))
            for gone in [s for s in self._slots if s > len(rail)]:
                self._slots.pop(gone).remove()
            self.slot_count = len(rail)
        for entry in rail:
            slot, entry = int(entry["slot"]), shown_entry(entry, self._causes)
            view = self._slots.get(slot)
            if view is None or view.shape != slot_shape(entry):
                if view is not None:
                    view.remove()
                self._slots[slot] = self._build_slot(entry)
                self.builds[slot] = self.builds.get(slot, 0) + 1
        leds = snap.get("leds") or {}
        for name, (box, colour) in self._coupler_leds.items():
            pattern = leds.get(name, "off")
            self._set_led(name, box, colour, pattern, t_us)
            self._set_text(name, self._coupler_labels[name],
                           f"{name} {PATTERN_WORDS.get(pattern, pattern)}")
        if self._legend is not None:
            self._set_text("legend", self._legend, module_led_legend(leds))
        for view in self._slots.values():
            for key, (box, colour) in view.leds.items():
                self._set_led(key, box, colour, leds.get(key, "off"), t_us)
        self._update_controls(snap)
        return resized

    def _set_led(self, key: str, box: viser.BoxHandle, colour: str, pattern: str,
                 t_us: int) -> None:
        rgb = led_color(colour, pattern, t_us)
        if self._colors.get(key) != rgb:
            box.color = rgb
            self._colors[key] = rgb

    def _set_text(self, key: str, label: viser.LabelHandle, text: str) -> None:
        if self._texts.get(key) != text:
            label.text = text
            self._texts[key] = text

    def _update_controls(self, snap: Mapping[str, Any]) -> None:
        rotary = snap.get("rotary_switch")
        if self._rotary is not None and rotary != self._rotary_value:
            self._rotary.text = f"ADDR {rotary}"
            self._rotary_value = rotary
        pressed = bool((snap.get("cnf") or {}).get("pressed"))
        if self._cnf is not None and pressed != self._cnf_pressed:
            self._cnf.color = CNF_PRESSED if pressed else CNF_IDLE
            self._cnf_pressed = pressed

    def led_colors(self) -> dict[str, RGB]:
        """The colour each LED shows now (for tests)."""
        return dict(self._colors)

    def drawn_slots(self) -> dict[int, str | None]:
        """The module type drawn in each slot, None for an empty one (for tests)."""
        return {slot: view.shape[0] for slot, view in self._slots.items()}


def slot_note(entry: Mapping[str, Any]) -> str:
    if not entry.get("plugged", True):
        return "unplugged"
    if not entry.get("powered", True):
        return "power off"
    detected = entry.get("detected_as")
    if detected is not None and detected != entry.get("type"):
        return f"seen {detected}"
    number = entry.get("module_number")
    if number is not None and number != entry.get("slot"):
        return f"bus #{number}"  # an empty slot before it shifts the bus numbering
    return ""
