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

A full step that does run leaves out, per module, what would write the same values again
(:class:`ModuleMemo`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from devices.cpx.addressing import AddressSpace
from devices.cpx.catalog import ModuleType
from devices.cpx.diagnosis import ActiveError
from devices.cpx.faults import Injected
from devices.cpx.leds import LedState
from devices.cpx.messages import DiagMessage
from devices.cpx.modules import CpxModule, ModuleFault, Monitors
from devices.stillness import Backoff, value_key_for

if TYPE_CHECKING:
    from devices.cpx.device import CpxEEc
    from devices.od import ObjectDictionary, OdEntry

# Identity, the dictionary (its stored values change only by writes, which touch the model),
# the event queue (compared by length) and this bookkeeping; ``units`` is [bus, *modules].
NOT_STATE = frozenset({"device_id", "rng", "now_us", "events", "od", "units", "_touched",
                       "_still", "_memo", "SKIP_STILL"})
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

    __slots__ = ("clock", "dt", "skipped", "skipped_at_check")

    def __init__(self) -> None:
        super().__init__()
        self.dt: int | None = None
        self.clock: tuple[Any, ...] = ()
        self.skipped = 0  # steps skipped so far (tests check that skipping happened)
        self.skipped_at_check = 0

    def touched(self) -> None:
        """Touched from outside: a quiet model (it skipped since the last check) is checked
        at the next chance; a model touched again before a passed check was of use (outputs
        changing every cycle or two) waits longer, so it does not pay a check per step."""
        if self.dt is not None and self.skipped == self.skipped_at_check:
            self.checked(False)
        elif self.dt is not None:
            self.restart()
        self.dt = None


class StillStepping:
    """``step`` of :class:`~devices.cpx.device.CpxEEc`: a full step (``_full_step``) or, when
    it would repeat a full step that changed nothing, none (see the module's docstring)."""

    SKIP_STILL = True  # False: every step in full (tests/hardening/test_still_cpx.py)
    _touched: bool
    _still: StillSteps
    _memo: ModuleMemo

    def _init_still(self) -> None:
        self._touched = True  # something from outside may have changed the model
        self._still = StillSteps()
        self._memo = ModuleMemo()

    def touch(self) -> None:
        """Something from outside may have changed the model: the next step runs in full."""
        self._touched = True

    def apply(self, action: str, args: Mapping[str, Any], module: int | None = None) -> Any:
        self._touched = True
        return super().apply(action, args, module)  # type: ignore[misc]

    def _announce_writes(self, od: ObjectDictionary) -> None:
        """Every write into the dictionary touches the model; an output object written with
        the value it has (a master's process image every cycle) changes nothing."""
        def before(entry: OdEntry, value: Any) -> None:
            output = 0x7000 <= entry.index <= 0x70FF and entry.getter is not None
            if not output or entry.getter() != value:
                self._touched = True
        od.announce_writes(before, [e for e in od if e.access.writable])

    def step(self: CpxEEc, now_us: int) -> None:
        dt_us = now_us - self.now_us
        if dt_us < 0:  # DeviceModel.step, inline (the still step is mostly calls)
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {self.now_us})")
        self.now_us = now_us
        still = self._still
        check = False
        if self._touched:  # a full step, not checked: the touch's changes happen in it
            self._touched = False
            still.touched()
        else:
            if still.dt == dt_us and self.SKIP_STILL and still.clock == self.clock_key_now():
                still.skipped += 1  # a repeat of a step that changed nothing
                return
            check = self.SKIP_STILL and still.due()
        before = (state_key(self), clock_key(self)) if check else None
        queued = len(self.events.items)
        self._full_step(dt_us)
        still.dt = None
        if before is not None:
            settled = (not self._touched and len(self.events.items) == queued
                       and state_key(self) == before[0])
            still.checked(settled)
            if settled:
                still.dt, still.clock, still.skipped_at_check = dt_us, before[1], still.skipped


class ModuleMemo:
    """A full step (one that runs because something changed) skips a module's drive, sample or
    fault search whose reads are as last time and whose images are as that call left them:
    calling it again would write the same values (``drive_outputs``, ``sample_inputs``) or
    return the same list (``faults``). Each ``*_reads`` method of CpxModule sits next to the
    method it covers and lists what that method reads; the module object itself is part of the
    key (its type never changes; a replaced module is a new object). The 1CI's outputs are
    always driven (its control bits have edges) and its inputs always sampled (it counts)."""

    __slots__ = ("_seen",)

    def __init__(self) -> None:
        self._seen: dict[tuple[str, int], tuple[CpxModule, tuple[Any, ...], Any]] = {}

    def drive(self, module: CpxModule, values: Sequence[int], supply_ok: bool) -> None:
        if module.is_counter or not module.mtype.outputs:
            module.drive_outputs(values, supply_ok)
            return
        reads = module.output_reads(values, supply_ok)
        seen = self._seen.get(("out", module.number))
        if seen is not None and seen[0] is module and seen[1] == reads \
                and seen[2] == (module.commanded, module.energised, module.driven):
            return
        module.drive_outputs(values, supply_ok)
        self._seen[("out", module.number)] = (
            module, reads, (list(module.commanded), list(module.energised), list(module.driven)))

    def sample(self, module: CpxModule) -> None:
        if module.is_counter or not module.mtype.inputs:
            module.sample_inputs()
            return
        reads = module.sample_reads()
        seen = self._seen.get(("in", module.number))
        if seen is not None and seen[0] is module and seen[1] == reads \
                and seen[2] == module.in_values:
            return
        module.sample_inputs()
        self._seen[("in", module.number)] = (module, reads, list(module.in_values))

    def faults(self, module: CpxModule, monitors: Monitors, supply_ok: bool
               ) -> list[ModuleFault]:
        reads = module.fault_reads(monitors, supply_ok)
        seen = self._seen.get(("faults", module.number))
        if seen is not None and seen[0] is module and seen[1] == reads:
            return list(seen[2])
        found = module.faults(monitors, supply_ok)
        self._seen[("faults", module.number)] = (module, reads, tuple(found))
        return found
