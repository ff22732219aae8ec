"""Which pattern each TRS-CAT LED shows (seed 001 §8), and the bank that reports changes.

RUN, ERROR and LINK-ACT follow ETG.1300 (§8.1); BUS green on = TRS bus active (§8.2), off at
start-up and after an irreversible TRS bus error; the yellow I/O LEDs show the logic state of
their line (§8.3); +24Vdc green on = field supply present and in range (§8.4).
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.ethercat import AlState
from devices.leds import RUN_BY_STATE, LedPattern, link_led
from devices.trscat.esm import ErrorKind

RUN = "RUN"
ERROR = "ERROR"
LINK_IN = "LINK-ACT IN"
LINK_OUT = "LINK-ACT OUT"
BUS = "BUS"
FIELD = "+24V"
IO_LED = "I/O {}"  # §10: the terminals are labelled I/O 1 .. I/O 16

# ETG.1300 ERR indicator: blinking = invalid configuration (a refused request), single flash =
# local error (the device left OP on its own: sync error), double flash = process-data
# watchdog timeout, on = application controller failure (0x6100 deadlock).
ERROR_BY_KIND: dict[ErrorKind, LedPattern] = {
    ErrorKind.NONE: LedPattern.OFF,
    ErrorKind.REFUSED: LedPattern.BLINKING,
    ErrorKind.LOCAL: LedPattern.SINGLE_FLASH,
    ErrorKind.WATCHDOG: LedPattern.DOUBLE_FLASH,
    ErrorKind.APPLICATION: LedPattern.ON,
}


def _io_names(count: int) -> tuple[str, ...]:
    return _IO_NAMES[:count]


_IO_NAMES = tuple(IO_LED.format(n) for n in range(1, 17))


def _on(lit: bool) -> LedPattern:
    return LedPattern.ON if lit else LedPattern.OFF


@dataclass(frozen=True)
class LedInputs:
    powered: bool
    state: AlState
    error: ErrorKind
    deadlocked: bool
    link_in: bool
    link_out: bool
    activity: bool
    bus_running: bool
    field_ok: bool
    io_mask: int  # logic levels of the integrated lines, bit n = I/O n + 1
    io_count: int = 16


def wanted_patterns(s: LedInputs) -> dict[str, LedPattern]:
    if not s.powered:
        off = dict.fromkeys((RUN, ERROR, LINK_IN, LINK_OUT, BUS, FIELD), LedPattern.OFF)
        off.update(dict.fromkeys(_io_names(s.io_count), LedPattern.OFF))
        return off
    error = LedPattern.ON if s.deadlocked else ERROR_BY_KIND[s.error]
    out = {RUN: RUN_BY_STATE[s.state], ERROR: error,
           LINK_IN: link_led(True, s.link_in, s.activity),
           LINK_OUT: link_led(True, s.link_out, s.activity and s.link_out),
           BUS: _on(s.bus_running), FIELD: _on(s.field_ok)}
    out.update({name: _on(bool(s.io_mask >> i & 1))
                for i, name in enumerate(_io_names(s.io_count))})
    return out
