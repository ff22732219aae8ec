"""When a CPX-E-EC step may be skipped: the step that repeats a still one (docs/cpx-e-ec.md).

A CPX-E-EC idle in OP does the same nothing every millisecond: it drives the outputs it drove,
samples the inputs it sampled, finds the faults it found and shows the LEDs it showed. A full
step is *still* when it emitted no event and :func:`state_key` — a value copy of everything
the model holds but its identity, its dictionary and this bookkeeping — is the same after it
as before. The next step is then skipped while

- nothing touched the model since (every command, AL control, cable, power, DC fault, taken
  emergency and object write marks it touched; a write of an output object with the value it
  already has does not, as it changes nothing),
- the step has the same length (the counter module counts ``rate * dt``),
- and :func:`clock_key` is the same: the ESM's state and code (the wire's face can refuse an
  AL control on the ESM itself) and every comparison of the clock a step makes — the Sync
  Manager watchdog, the sync error counter, LA IN / LA OUT traffic, "no master" and the 20 ms
  bridging of U_EL/SEN. The master's frames move ``last_frame_us`` / ``last_pd_us`` /
  ``sync_counter`` every cycle without touching the model: a step reads them only through
  those comparisons, so equal comparisons mean an equal step.

A step reads the clock nowhere else but in time stamps of what it emits (a diagnosis message,
an LED or state event), and a still step emits nothing. The LEDs are patterns (ETG.1300 names),
not lamp phases: a blinking LED is a constant pattern, not a change per step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devices.cpx.addressing import AddressSpace
from devices.cpx.catalog import ModuleType
from devices.cpx.diagnosis import ActiveError
from devices.cpx.faults import Injected
from devices.cpx.leds import LedState
from devices.cpx.messages import DiagMessage
from devices.cpx.modules import ModuleFault
from devices.stillness import Backoff, value_key_for

if TYPE_CHECKING:
    from devices.cpx.device import CpxEEc

# Identity, the dictionary (its stored values change only by writes, which touch the model),
# the event queue (compared by length) and this bookkeeping; ``units`` is [bus, *modules].
NOT_STATE = frozenset({"device_id", "rng", "now_us", "events", "od", "units", "_touched",
                       "_touch_streak", "_still", "SKIP_STILL"})
# Frozen dataclasses of numbers, strings, enums and tuples: compared as they are (checked by
# tests/hardening/test_still_cpx.py), not field by field.
VALUES = (ModuleType, LedState, ActiveError, ModuleFault, DiagMessage, Injected, AddressSpace)
_value = value_key_for(VALUES)


def state_key(dev: CpxEEc) -> tuple[Any, ...]:
    """Everything a step can change, by value."""
    return tuple((k, _value(v)) for k, v in vars(dev).items() if k not in NOT_STATE)


def clock_key(dev: CpxEEc) -> tuple[Any, ...]:
    """The ESM as it stands and every clock comparison a step makes, at ``dev.now_us``: the
    same methods the step asks."""
    esm = dev.esm
    return (esm.state, esm.error, esm.code, esm.requested, dev.pd_watchdog_expired(),
            dev.sync_error(), dev.traffic(), dev.master_silent(), dev.bridging_over())


class StillSteps(Backoff):
    """The last full step's length and clock key if it changed nothing (``dt`` None: it did,
    or it was not checked), and when to check again after a failed check."""

    __slots__ = ("clock", "dt", "skipped")

    def __init__(self) -> None:
        super().__init__()
        self.dt: int | None = None
        self.clock: tuple[Any, ...] = ()
        self.skipped = 0  # steps skipped so far (tests check that skipping happened)
