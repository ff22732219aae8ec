"""The TRS-CAT with its expansions and the CPX-E-EC with its modules, as 3D fronts.

TRS-CAT (seed 001): RUN, ERROR, LINK-ACT IN / OUT (ETG.1300), green BUS, green +24 V and the
16 yellow I/O LEDs of the integrated channels, then one plate per expansion with its type and
what the node found there (0xF050) when that differs from what the master configured (0xF030).
CPX-E-EC (seed 002 tables 11-13): Run, Error, LA IN, LA OUT, PS, PL, SF, M in the colour the
model reports (Run / Error also orange), then one plate per module with a red error LED and a
yellow LED per channel. The seed names no per-channel LED in the snapshot, so the plates show
the channel signal (inputs for input modules, driven outputs for output modules) and light the
module's error LED as the model says (the module snapshot's "error_led": the worst cause the
bus module diagnoses on it and its channels), as the modules' own LEDs do: a short on an
output switched off is wired but not seen (docs/cpx-e-ec.md choice 30).

A plate is one module wide (1.0) and its labels keep their size on screen: a type longer
than TYPE_LINE characters ("4AI-U-I") takes two lines ("4AI-" / "U-I") hanging from under
the plate's number, so that neighbouring types do not run into each other at the default
camera (tests/app/test_line_labels.py). A module's note under its plate ("short 0-7", "sensor
short") takes at most two lines of NOTE_LINE characters, so that the notes of neighbouring
faulted modules stay apart and clear of the blink words under the CPX.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import viser

from app.ui.line.bodies import BODY, Body, blink_words, wrap
from app.ui.rail_scene import BODY_D, BODY_H

MODULE_W = 1.0
TRS_W = 2.6
CPX_W = 1.8
TRS_LEDS = (("RUN", "green"), ("ERROR", "red"), ("LINK-ACT IN", "green"),
            ("LINK-ACT OUT", "green"), ("BUS", "green"), ("+24V", "green"))
CPX_LEDS = ("Run", "Error", "LA IN", "LA OUT", "PS", "PL", "SF", "M")
CPX_COLOURS = {"Run": "green", "Error": "red", "LA IN": "green", "LA OUT": "green",
               "PS": "green", "PL": "green", "SF": "red", "M": "yellow"}
CHANNEL_LED = (0.24, 0.1, 0.15)
TYPE_LINE = 5  # characters of a plate's type per line: "16DI" on one, "4AI-U-I" on two
TYPE_Z = 1.5  # top of a plate's type, under its number
ERROR_LED_Z = 0.72  # a CPX plate's error LED, under a two-line type
EXP_NOTE_Z = 0.2  # a TRS-CAT expansion's note, clear of the cables at the plate's foot
NOTE_TOP_Z = -1.6  # a CPX module's note hangs from under the lowest channel LED (row 8)
NOTE_LINE = 7  # characters of a CPX module's note per line: "short 3" on one, "sensor" / "short"


def ident_text(value: int | str) -> str:
    """A §9.3.2 ASCII ident (0x494F2D45 -> "IO-E"); 0 is an empty position."""
    number = int(value, 16) if isinstance(value, str) else int(value)
    if number == 0:
        return "-"
    raw = number.to_bytes(4, "big")
    if all(32 <= b < 127 for b in raw):
        return raw.decode("ascii")
    return f"0x{number:08X}"


def expansion_note(snap: Mapping[str, Any], position: int) -> str:
    """What a still must say about expansion ``position`` (1-based): another type in 0xF050
    (found) than in 0xF030 (configured by the master), not found, and the application errors
    raised for its slot."""
    slots = snap.get("slots") or []
    entry = slots[position] if position < len(slots) else {}
    # §9.3.2: sub 0 is the count and sub 1 the integrated module, so expansion n is sub n + 1.
    sub = position + 1
    f030, f050 = snap.get("f030") or [], snap.get("f050") or []
    configured = f030[sub] if sub < len(f030) else 0
    found = f050[sub] if sub < len(f050) else 0
    # Every module is unserviced while the TRS bus is off (node powered off, still
    # detecting): that is the node's state, in the header; a plate says "not seen" only for
    # its own module: an empty position, or a fitted module the running bus does not reach.
    bus_running = (snap.get("trs_bus") or {}).get("state", "running") == "running"
    lines = []
    if "type" in entry and entry["type"] is None:
        lines.append("not seen")
    elif configured and found and configured != found:
        lines.append(f"cfg {ident_text(configured)}")
    elif bus_running and not entry.get("serviced", True):
        lines.append("not seen")
    # §9.3.7 application errors name the slot they concern (0xA000 configuration error).
    lines += [str(a.get("code", "")) for a in snap.get("alarms") or []
              if isinstance(a, Mapping) and a.get("slot") == position]
    return "\n".join(lines)


def short_type(name: str) -> str:
    return name.removeprefix("TRS-").removeprefix("CPX-E-")


def module_error(module: Mapping[str, Any]) -> str:
    """The reason the module's red LED is on, "" when it is off."""
    reason, channels = _error_parts(module)
    return f"{reason} {channel_list(channels)}" if channels else reason


def module_note(module: Mapping[str, Any]) -> str:
    """:func:`module_error` under the plate, on at most two lines of NOTE_LINE characters (the
    blink words of the CPX hang below): the reason, then the channels where they fit on a
    line, else their count ("short" / "6 ch."; the Slave tab lists every one)."""
    reason, channels = _error_parts(module)
    if not channels:
        return wrap(reason, NOTE_LINE)
    listed = channel_list(channels)
    if len(reason) + 1 + len(listed) <= NOTE_LINE:
        return f"{reason} {listed}"
    return f"{reason}\n{listed if len(listed) <= NOTE_LINE else f'{len(channels)} ch.'}"


# The plate's words for the cause a module's red LED shows. Which cause that is (the worst
# diagnosed) and on which channels is the model's: the module snapshot's "error_led"
# (devices/cpx/leds.py MODULE_LED_CAUSES, docs/cpx-e-ec.md choice 30).
LED_WORDS = {"module_failure": "failed", "short_circuit_sensor_supply": "sensor short",
             "short_circuit_outputs": "short", "wire_break": "wire",
             "undervoltage_out": "U_OUT low"}


def _error_parts(module: Mapping[str, Any]) -> tuple[str, list[int]]:
    """The words and channels of the module's red LED, as its snapshot's "error_led" says."""
    led = module.get("error_led") or {}
    cause = led.get("cause")
    if led.get("pattern", "off") == "off" or cause is None:
        return "", []
    return LED_WORDS.get(str(cause), str(cause)), [int(c) for c in led.get("channels") or []]


# The Slave tab's words for why a wired cause is not diagnosed. Which causes those are and
# why is the model's: the module snapshot's "undiagnosed" (devices/cpx/unseen.py
# UNSEEN_REASONS). Every reason has words (tests/browser/test_line_text.py checks the two
# tables' keys; one without would show its id): an instructor whose fault shows nowhere needs
# to know which switch or state hides it (0x2400 is the bus module's parameter, seed 002
# Tab. 27).
REASON_WORDS = {"output_off": "output off", "current_range": "current range",
                "no_load_supply": "no load supply",
                "signal_range": "signal range", "no_application": "bus module not running",
                "module_failed": "module failed", "monitor_off": "0x2400 monitor off",
                "pending": "next cycle"}


def module_fault_parts(module: Mapping[str, Any]) -> tuple[str, list[str]]:
    """The Slave tab's Fault column as plain texts: what the red LED says, then what is
    wired but not diagnosed, and why ("short 3 (output off: not diagnosed)"), so that an
    instructor who injected a fault is not left wondering why SF and 0x1001 stay quiet. The
    second part names a cause the device does not report: the instructor's only
    (docs/classroom.md)."""
    hidden = []
    for entry in module.get("undiagnosed") or []:
        cause, reason = str(entry.get("cause")), str(entry.get("reason"))
        channels = [int(c) for c in entry.get("channels") or []]
        what = LED_WORDS.get(cause, cause)
        what = f"{what} {channel_list(channels)}" if channels else what
        why = REASON_WORDS.get(reason, reason)
        hidden.append(f"{what} ({why}: not diagnosed)")
    return module_error(module), hidden


def channel_list(channels: Sequence[int]) -> str:
    """Channel numbers as a field engineer writes them: a run of three or more by its ends
    ([0, 1, 2, 3, 5] -> "0-3,5")."""
    numbers = sorted({int(c) for c in channels})
    parts: list[str] = []
    i = 0
    while i < len(numbers):
        j = i
        while j + 1 < len(numbers) and numbers[j + 1] == numbers[j] + 1:
            j += 1
        if j - i >= 2:
            parts.append(f"{numbers[i]}-{numbers[j]}")
        else:
            parts.extend(str(n) for n in numbers[i:j + 1])
        i = j + 1
    return ",".join(parts)


def channel_levels(module: Mapping[str, Any]) -> list[bool]:
    """The signal behind each channel LED (digital modules only; analog ones have none)."""
    kind = str(module.get("short", ""))
    if "DI" in kind and "AI" not in kind:
        return [bool(v) for v in module.get("inputs") or []]
    if "DO" in kind and "AO" not in kind:
        return [bool(v) for v in module.get("driven") or module.get("outputs") or []]
    return []


class TrsCatBody(Body):
    title = "TRS-CAT"

    def __init__(self, server: viser.ViserServer, device_id: str, x0: float, z0: float,
                 snap: Mapping[str, Any]) -> None:
        super().__init__(server, device_id, x0, z0)
        # An empty position (type None) gets the plate of the module configured there.
        self.expansions = [str(s.get("type") or s.get("configured") or "-")
                           for s in (snap.get("slots") or [])[1:]]
        self.width = TRS_W + MODULE_W * len(self.expansions)

    def build(self) -> None:
        # The frame spans node + expansions; the node's own body is narrower.
        p = self.paint
        self.clickables.append(p.box("body", (TRS_W * 0.96, BODY_D, BODY_H),
                                     (self.x0 + TRS_W / 2, 0.0, self.z0), BODY))
        self.build_frame()
        p.label("title", self.title, self.at(TRS_W / 2, 1.72), anchor="center-center",
                scale=0.85)
        for i, (name, _colour) in enumerate(TRS_LEDS):
            z = 1.2 - i * 0.36
            p.led(name, self.at(0.3, z))
            p.label(f"name_{i}", name, self.at(0.52, z), scale=0.66)
        p.label("io", "I/O 1-8, 9-16", self.at(0.18, -1.0), scale=0.64)
        for ch in range(16):
            row, col = divmod(ch, 8)
            p.led(f"I/O {ch + 1}", self.at(0.3 + col * 0.29, -1.38 - row * 0.3),
                  CHANNEL_LED)
        for n, kind in enumerate(self.expansions, start=1):
            x = TRS_W + (n - 0.5) * MODULE_W
            self.clickables.append(p.box(f"exp{n}", (MODULE_W * 0.92, BODY_D, BODY_H),
                                         (self.x0 + x, 0.0, self.z0), BODY))
            p.label(f"exp{n}_n", str(n), self.at(x, 1.72), anchor="center-center", scale=0.8)
            p.label(f"exp{n}_t", wrap(short_type(kind), TYPE_LINE), self.at(x, TYPE_Z),
                    anchor="top-center", scale=0.68)
            p.label(f"exp{n}_note", "", self.at(x, EXP_NOTE_Z), anchor="center-center",
                    scale=0.66)

    def update(self, snap: Mapping[str, Any], t_us: int) -> str:
        leds = snap.get("leds") or {}
        for name, colour in TRS_LEDS:
            self.paint.set_led(name, colour, str(leds.get(name, "off")), t_us)
        for ch in range(1, 17):
            self.paint.set_led(f"I/O {ch}", "yellow", str(leds.get(f"I/O {ch}", "off")), t_us)
        for n in range(1, len(self.expansions) + 1):
            self.paint.set_text(f"exp{n}_note", expansion_note(snap, n))
        names = [n for n, _c in TRS_LEDS] + [f"I/O {c}" for c in range(1, 17)]
        return blink_words((n, str(leds.get(n, "off"))) for n in names)


class CpxBody(Body):
    title = "CPX-E-EC"

    def __init__(self, server: viser.ViserServer, device_id: str, x0: float, z0: float,
                 snap: Mapping[str, Any]) -> None:
        super().__init__(server, device_id, x0, z0)
        modules: Sequence[Mapping[str, Any]] = snap.get("modules") or []
        self.modules = [(int(m.get("module", i + 1)), str(m.get("short") or m.get("type")),
                         len(channel_levels(m))) for i, m in enumerate(modules)]
        self.width = CPX_W + MODULE_W * len(self.modules)

    def build(self) -> None:
        p = self.paint
        self.clickables.append(p.box("body", (CPX_W * 0.96, BODY_D, BODY_H),
                                     (self.x0 + CPX_W / 2, 0.0, self.z0), BODY))
        self.build_frame()
        p.label("title", self.title, self.at(CPX_W / 2, 1.72), anchor="center-center",
                scale=0.8)
        for i, name in enumerate(CPX_LEDS):
            z = 1.25 - i * 0.36
            p.led(name, self.at(0.3, z))
            p.label(f"name_{i}", name, self.at(0.52, z), scale=0.66)
        for i, (number, short, channels) in enumerate(self.modules):
            x = CPX_W + (i + 0.5) * MODULE_W
            self.clickables.append(p.box(f"m{number}", (MODULE_W * 0.92, BODY_D, BODY_H),
                                         (self.x0 + x, 0.0, self.z0), BODY))
            p.label(f"m{number}_n", str(number), self.at(x, 1.72), anchor="center-center",
                    scale=0.8)
            p.label(f"m{number}_t", wrap(short, TYPE_LINE), self.at(x, TYPE_Z),
                    anchor="top-center", scale=0.66)
            p.led(f"m{number}.error", self.at(x, ERROR_LED_Z), (0.3, 0.12, 0.18))
            for ch in range(channels):
                row, col = ch % 8, ch // 8
                p.led(f"m{number}.{ch}", self.at(x - 0.17 + col * 0.34, 0.45 - row * 0.27),
                      CHANNEL_LED)
            p.label(f"m{number}_note", "", self.at(x, NOTE_TOP_Z), anchor="top-center",
                    scale=0.64)

    def update(self, snap: Mapping[str, Any], t_us: int) -> str:
        states = snap.get("led_states") or {}
        leds = snap.get("leds") or {}
        shown: list[tuple[str, str]] = []
        for name in CPX_LEDS:
            state = states.get(name) or {}
            pattern = str(state.get("pattern", leds.get(name, "off")))
            colour = str(state.get("colour", CPX_COLOURS[name]))
            self.paint.set_led(name, colour, pattern, t_us)
            shown.append((name if colour == CPX_COLOURS[name] else f"{name} ({colour})",
                          pattern))
        by_number = {int(m.get("module", 0)): m for m in snap.get("modules") or []}
        for number, _short, channels in self.modules:
            module = by_number.get(number, {})
            led = module.get("error_led") or {}
            self.paint.set_led(f"m{number}.error", str(led.get("colour", "red")),
                               str(led.get("pattern", "off")), t_us)
            self.paint.set_text(f"m{number}_note", module_note(module))
            levels = channel_levels(module)
            for ch in range(channels):
                lit = ch < len(levels) and levels[ch]
                self.paint.set_led(f"m{number}.{ch}", "yellow", "on" if lit else "off", t_us)
        return blink_words(shown)
