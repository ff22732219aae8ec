"""The CPX-E-EC's LEDs: what each shows, as tables (seed 002 §2.1.6, §2.4.1, Tab. 11-13).

Network LEDs: Run (green, orange), Error (red, orange), LA IN / LA OUT (green). System LEDs
(§2.1.6, Fig. 3): PS (green, U_EL/SEN), PL (green, U_OUT), SF (red, system fault), M (yellow,
forcing); the seed refers their patterns to the CPX-E system description, FieldRig's reading
is in docs/cpx-e-ec.md. Timings are ETG.1300's (devices/leds.py).

Colour is part of an LED's state. Run and Error are two-colour LEDs: events and the snapshot's
``leds`` name one channel per colour ("Run" = green, "Run.orange"; "Error" = red,
"Error.orange"), the way the FastCAT's module LEDs are "N.red" / "N.yellow"; ``led_states``
gives each physical LED with its pattern and colour. A dashboard draws one LED body: orange
where the ".orange" channel is lit, the LED's own colour where the plain channel is lit.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from devices.events import Event, LedChanged
from devices.leds import LedPattern


class Colour(enum.Enum):
    GREEN = "green"
    RED = "red"
    ORANGE = "orange"
    YELLOW = "yellow"


@dataclass(frozen=True)
class LedState:
    pattern: LedPattern
    colour: Colour

    @property
    def lit(self) -> bool:
        return self.pattern is not LedPattern.OFF


def _s(pattern: LedPattern, colour: Colour) -> LedState:
    return LedState(pattern, colour)


class RunShows(enum.Enum):
    INIT = "Init"
    PREOP = "Pre-Operational"
    SAFEOP = "Safe-Operational"
    OP = "Operational"
    BOOT = "Bootstrap"
    BOOTLOADER = "OS bootloader or firmware update active"


# Tab. 11 "Рабочее состояние EtherCAT [Run]".
RUN_TABLE: dict[RunShows, LedState] = {
    RunShows.OP: _s(LedPattern.ON, Colour.GREEN),
    RunShows.PREOP: _s(LedPattern.BLINKING, Colour.GREEN),
    RunShows.SAFEOP: _s(LedPattern.SINGLE_FLASH, Colour.GREEN),
    RunShows.BOOT: _s(LedPattern.FLICKERING, Colour.GREEN),
    RunShows.BOOTLOADER: _s(LedPattern.ON, Colour.ORANGE),
    RunShows.INIT: _s(LedPattern.OFF, Colour.GREEN),
}


class ErrorShows(enum.Enum):
    NONE = "No error"
    AC_FAILURE = "Application Controller Failure"
    INVALID_CONFIGURATION = "Invalid Configuration, no network connection"
    SYNC_ERROR = "Unsolicited State Change OP -> SAFEOP (sync error)"
    WATCHDOG = "Application / Sync Manager watchdog timeout"
    RESERVED = "reserved"
    BOOTING_ERROR = "Booting Error (Application Controller flash checksum)"
    BOOTLOADER = "OS bootloader or firmware update active"


# Tab. 12 "Ошибка EtherCAT [Error]". Triple flash is "reserved": no cause drives it.
ERROR_TABLE: dict[ErrorShows, LedState] = {
    ErrorShows.AC_FAILURE: _s(LedPattern.ON, Colour.RED),
    ErrorShows.INVALID_CONFIGURATION: _s(LedPattern.BLINKING, Colour.RED),
    ErrorShows.SYNC_ERROR: _s(LedPattern.SINGLE_FLASH, Colour.RED),
    ErrorShows.WATCHDOG: _s(LedPattern.DOUBLE_FLASH, Colour.RED),
    ErrorShows.RESERVED: _s(LedPattern.TRIPLE_FLASH, Colour.RED),
    ErrorShows.BOOTING_ERROR: _s(LedPattern.FLICKERING, Colour.RED),
    ErrorShows.BOOTLOADER: _s(LedPattern.ON, Colour.ORANGE),
    ErrorShows.NONE: _s(LedPattern.OFF, Colour.RED),
}
# When several apply, the most severe wins (the order of this tuple).
ERROR_PRIORITY = (ErrorShows.AC_FAILURE, ErrorShows.BOOTING_ERROR, ErrorShows.BOOTLOADER,
                  ErrorShows.INVALID_CONFIGURATION, ErrorShows.WATCHDOG,
                  ErrorShows.SYNC_ERROR, ErrorShows.NONE)


class LinkShows(enum.Enum):
    LINK = "Network connection OK"
    TRAFFIC = "Data exchange (traffic)"
    NO_LINK = "No network connection"


# Tab. 13 "Состояние соединения [LA IN], [LA OUT]" (green).
LINK_TABLE: dict[LinkShows, LedState] = {
    LinkShows.LINK: _s(LedPattern.ON, Colour.GREEN),
    LinkShows.TRAFFIC: _s(LedPattern.FLICKERING, Colour.GREEN),
    LinkShows.NO_LINK: _s(LedPattern.OFF, Colour.GREEN),
}


class SupplyShows(enum.Enum):
    OK = "voltage present"
    UNDERVOLTAGE = "voltage below tolerance"
    ABSENT = "no voltage"


# PS (U_EL/SEN) and PL (U_OUT), green (§2.1.6); FieldRig: blinking below the tolerance.
SUPPLY_TABLE: dict[SupplyShows, LedState] = {
    SupplyShows.OK: _s(LedPattern.ON, Colour.GREEN),
    SupplyShows.UNDERVOLTAGE: _s(LedPattern.BLINKING, Colour.GREEN),
    SupplyShows.ABSENT: _s(LedPattern.OFF, Colour.GREEN),
}

# SF, red (§2.1.6): flashes as many times as the class of the most severe error (CPX-E system
# description: 1 simple, 2 standard diagnosis, 3 hardware), off without error.
SF_BY_CLASS: dict[int, LedState] = {
    0: _s(LedPattern.OFF, Colour.RED),
    1: _s(LedPattern.SINGLE_FLASH, Colour.RED),
    2: _s(LedPattern.DOUBLE_FLASH, Colour.RED),
    3: _s(LedPattern.TRIPLE_FLASH, Colour.RED),
}
# M, yellow (§2.1.6): on while something is forced.
M_TABLE: dict[bool, LedState] = {True: _s(LedPattern.ON, Colour.YELLOW),
                                 False: _s(LedPattern.OFF, Colour.YELLOW)}

# A module's red error LED (§2.4.1 refers the module LEDs to the CPX-E system description;
# FieldRig, docs/cpx-e-ec.md choice 30): on while the bus module diagnoses a cause on the
# module. One LED shows one cause, the worst diagnosed, in this order (devices/cpx/codes.py
# CAUSES), with that cause's channels. U_OUT low is diagnosed on each module with outputs
# (Tab. 21-24 name the module), so their LEDs light as well as the bus module's PL.
MODULE_LED_CAUSES = ("module_failure", "short_circuit_sensor_supply", "short_circuit_outputs",
                     "wire_break", "undervoltage_out")
MODULE_ERROR_LED: dict[bool, LedState] = {True: _s(LedPattern.ON, Colour.RED),
                                          False: _s(LedPattern.OFF, Colour.RED)}


def module_error_led(diagnosed: Sequence[tuple[str, int | None]]) -> dict[str, object]:
    """A module's red LED from what is diagnosed on it, (cause, channel) pairs: its pattern
    and colour, the cause it shows (None when dark) and that cause's channels."""
    causes = {cause for cause, _channel in diagnosed}
    shown = next((c for c in MODULE_LED_CAUSES if c in causes), None)
    state = MODULE_ERROR_LED[shown is not None]
    return {"pattern": state.pattern.value, "colour": state.colour.value, "cause": shown,
            "channels": sorted({ch for cause, ch in diagnosed
                                if cause == shown and ch is not None})}


LED_NAMES = ("Run", "Error", "LA IN", "LA OUT", "PS", "PL", "SF", "M")
BICOLOUR = {"Run": Colour.GREEN, "Error": Colour.RED}  # own colour; the other one is orange
DARK: dict[str, LedState] = {"Run": RUN_TABLE[RunShows.INIT],
                             "Error": ERROR_TABLE[ErrorShows.NONE],
                             "LA IN": LINK_TABLE[LinkShows.NO_LINK],
                             "LA OUT": LINK_TABLE[LinkShows.NO_LINK],
                             "PS": SUPPLY_TABLE[SupplyShows.ABSENT],
                             "PL": SUPPLY_TABLE[SupplyShows.ABSENT],
                             "SF": SF_BY_CLASS[0], "M": M_TABLE[False]}


def channels(name: str, state: LedState) -> dict[str, LedPattern]:
    """The event / snapshot channels of one LED ("Run", "Run.orange")."""
    if name not in BICOLOUR:
        return {name: state.pattern}
    orange = state.colour is Colour.ORANGE
    return {name: LedPattern.OFF if orange else state.pattern,
            f"{name}.orange": state.pattern if orange else LedPattern.OFF}


@dataclass
class LedBank:
    """The LEDs' last states; emits LedChanged per channel only when its pattern changes."""

    device: str
    states: dict[str, LedState] = field(default_factory=lambda: dict(DARK))

    def update(self, t_us: int, wanted: Mapping[str, LedState],
               emit: Callable[[Event], None]) -> None:
        for name, state in wanted.items():
            if self.states[name] is state:  # table entries: the same object when unchanged
                continue
            before = channels(name, self.states[name])
            for channel, pattern in channels(name, state).items():
                if before[channel] is not pattern:
                    emit(LedChanged(t_us, self.device, led=channel, pattern=pattern.value))
            self.states[name] = state

    def channel_patterns(self) -> dict[str, str]:
        out: dict[str, str] = {}
        for name in LED_NAMES:
            out.update({c: p.value for c, p in channels(name, self.states[name]).items()})
        return out

    def snapshot(self) -> dict[str, dict[str, str]]:
        return {name: {"pattern": s.pattern.value, "colour": s.colour.value}
                for name, s in self.states.items()}
