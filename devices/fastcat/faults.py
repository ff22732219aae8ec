"""Alarm causes and the alarm latch of the FastCAT coupler (seed 000 §7, §7.5, §7.6).

An alarm *cause* is a condition present now: injected by an operator, or physical (a module
that does not answer, the Ethernet cable, the Tbus supply, a module's own alarm, the result of
the last scan). The coupler latches the first cause it finds (§7: "il primo allarme ricevuto,
che è la causa scatenante"), sends one emergency, puts every module in alarm and, for a coupler
alarm (§7.5) in SAFEOP or OP, falls back to PREOP with the 0x80XX code of §7.7; a module alarm
(§7.6) leaves the ESM where it is, so the Reset fault bit in the process data can clear it.
Later causes send nothing while an alarm is latched. A Reset fault edge (§6.17) clears a
resettable alarm, a resync (the line taken through INIT) any alarm, in both cases only once its
cause is gone; the next present cause is then latched with a new emergency. Cause -> code
mapping: docs/fastcat-coupler.md.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from devices.device import CommandError
from devices.ethercat import AlState, emergency_frame
from devices.events import AlarmChanged, EmergencySent, Event, LogLine, fmt_hex
from devices.fastcat.alarms import (
    COUPLER,
    EMERGENCY_CODE,
    EMERGENCY_REGISTER,
    MODULE,
    Alarm,
    al_status_meaning,
    parse_fault,
)
from devices.fastcat.catalog import module_type
from devices.fastcat.objects import MAX_MODULES
from devices.mdp import ident_mismatch

if TYPE_CHECKING:
    from devices.fastcat.cnf import BusScan
    from devices.fastcat.esm import Esm
    from devices.fastcat.modules import IoModule

MAX_ANALOG_MODULES = 8  # §2 "al massimo 8 moduli analogici"
MAILBOX_DEPTH = 16  # emergencies kept for the master while its mailbox is not running


class FaultsMixin:
    """Alarm handling of :class:`~devices.fastcat.coupler.FastCat`."""

    # Provided by FastCat (declared for type checkers).
    device_id: str
    now_us: int
    powered: bool
    booted: bool
    link: bool
    tbus_low: bool
    scan: BusScan | None
    esm: Esm
    alarm: Alarm | None
    injected: list[Alarm]
    edge_causes: list[Alarm]
    raised: list[Alarm]
    fresh_raised: list[Alarm]
    address_fault: bool
    slot_fault: bool  # 0x14 found at PREOP -> SAFEOP, cause while 0xF030 still disagrees
    configured: list[int]  # 0xF030, sub 0 = count
    address_check: int
    rotary_read: int
    master_address: int
    wire_station: int | None
    reset_bit: int
    mailbox: list[bytes]
    rail: list[IoModule | None]
    detected: list[tuple[int, str]]
    bound: list[IoModule]
    stored: list[str] | None
    _scan_causes_key: tuple[Any, ...] | None  # (detected, stored, causes) of the last call
    _answering: list[bool] | None  # who answered this step's exchange (None outside a step)
    _answer_cache: tuple[Any, ...] | None  # who answers, kept by bus.py
    _stepped: list[tuple[int, IoModule]] | None  # the modules this step's exchange stepped
    _quiet: bool  # the last search, in a step, found no cause (_still_quiet)

    if TYPE_CHECKING:  # defined by DeviceModel / FastCat; stubs here would shadow them
        def emit(self, event: Event) -> None: ...
        def modules(self) -> list[IoModule]: ...
        def _answers(self, n: int) -> bool: ...
        def _bus_table(self) -> list[IoModule | None]: ...
        def _refresh(self) -> None: ...
        def check_module_fault(self, symbol: str, module: int) -> None: ...

    def _present_causes(self) -> list[Alarm]:
        """Every alarm cause present now, in the order the coupler would report them."""
        return list(self._causes())

    def _causes(self) -> Iterator[Alarm]:
        """The causes in report order, lazily: the latch needs only the first one."""
        yield from self.edge_causes
        yield from self.injected
        if not self.link:
            yield Alarm(COUPLER, 0x13)
        if self.booted:
            yield from self._scan_causes()
        if self.address_fault and self.address_check and self._address_mismatch():
            yield Alarm(COUPLER, 0x12)
        if self.slot_fault:
            slot = self._slot_mismatch()
            if slot is not None:
                yield Alarm(COUPLER, 0x14, slot)
        if self._answering is None:  # outside a step: asked now, as _answers(n)
            bus = self._bus_table()
            answering = [m is not None and m.responds() for m in bus]
            cycle = [(n, m) for n, m in enumerate(bus, start=1) if m is not None
                     and answering[n - 1]]
        else:  # in a step: whom this step's exchange found answering (bus.py)
            assert self._answer_cache is not None
            _bus, answering, cycle, _silent = self._answer_cache
        if not all(answering):
            for n, (slot, name) in enumerate(self.detected, start=1):
                if not answering[n - 1]:
                    module = self.rail[slot - 1] if slot <= len(self.rail) else None
                    changed = module is not None and module.mtype.name != name
                    yield Alarm(COUPLER, 0x01 if changed else 0x04, n)
        if self.tbus_low and self.detected:
            yield Alarm(MODULE, 0x0C, 1)  # §7.6 LOW_VOLTAGE, byte 0 = first module
        for n, module in cycle:
            for code in module.physical_alarm_codes():
                yield Alarm(MODULE, code, n)
        yield from self.fresh_raised  # raised this exchange: an event, latch it as such
        for a in self.raised:
            if a.module <= len(self.bound) and answering[a.module - 1] \
                    and self.bound[a.module - 1].cause_present(a.code):
                yield a

    def _scan_causes(self) -> tuple[Alarm, ...]:
        """Causes in the last scan's result; they change only with ``detected`` / ``stored``."""
        key = self._scan_causes_key
        if key is not None and key[0] is self.detected and key[1] == self.stored:
            return key[2]
        names = [name for _slot, name in self.detected]
        out = []
        if not names:
            out.append(Alarm(COUPLER, 0x10))  # §7.5 NO_MOD
        if self.stored is not None:
            for i in range(max(len(names), len(self.stored))):
                if i >= len(names):
                    out.append(Alarm(COUPLER, 0x02, i + 1))  # §7.5 MODULE_NO_PRES
                    break
                if i >= len(self.stored) or names[i] != self.stored[i]:
                    out.append(Alarm(COUPLER, 0x01, i + 1))  # §7.5 MODULE_CHANGED
                    break
        analog = [n for n, name in enumerate(names, start=1)
                  if module_type(name).counts_as_analog]
        if len(analog) > MAX_ANALOG_MODULES:  # §7.5 0x15: byte 0 = the 8th analog module
            out.append(Alarm(COUPLER, 0x15, analog[MAX_ANALOG_MODULES - 1]))
        stored = None if self.stored is None else list(self.stored)
        self._scan_causes_key = (self.detected, stored, tuple(out))
        return tuple(out)

    def logical_address(self) -> int:
        """§6.19's «indirizzo logico assegnato dal master Ethercat»: the configured station
        address a wire master wrote (ESC 0x0010, whole: a value above 15 never matches the
        switch), else the built-in master's own setting (the rig file's ``master_address``)."""
        station = self.wire_station
        return self.master_address if station is None else station

    def _address_mismatch(self) -> bool:
        return self.rotary_read != self.logical_address()

    def _slot_mismatch(self) -> int | None:
        """§7.5 0x14: the first slot n where the master's 0xF030.n is not the 0xF050.n found
        (docs/fastcat-coupler.md "0xF030"); None when they agree or nothing is configured."""
        count = self.configured[0]
        if count == 0:
            return None
        pos = ident_mismatch(self.configured[1:count + 1],
                             [m.mtype.product_code for m in self.bound], zero_unchecked=True)
        return None if pos is None else pos + 1

    def _evaluate_alarms(self) -> None:
        if not self.powered or self.scan is not None or not self.booted:
            return
        if self.alarm is None:  # while one is latched, later causes report nothing (§7)
            if self._quiet and self._still_quiet():
                first = None
            else:
                first = next(self._causes(), None)
                # Found nothing in a step: kept while the next steps bring nothing new.
                self._quiet = first is None and self._answering is not None
            if first is not None:
                self._latch(first)
        # A module alarm raised while another is latched stays pending while its cause lasts.
        fresh = self.fresh_raised
        if fresh or self.raised:
            self.fresh_raised = []
            self.raised = [a for a in dict.fromkeys([*self.raised, *fresh])
                           if a == self.alarm or self._module_cause(a)]

    def _still_quiet(self) -> bool:
        """After a step's search found no cause: does this step's search find none either?
        Every cause but the modules' own is coupler state that only a command (a touch) or
        a scan changes, and FastCat.step clears ``_quiet`` on both; a module's level alarms
        change only with its own state, so only the modules this exchange stepped can have
        one now (a still module that was not stepped is as it was). Any doubt, or anything
        found: False, and the full search (in report order) decides."""
        stepped = self._stepped
        if self._answering is None or stepped is None or self.fresh_raised or self.raised:
            return False
        for _n, module in stepped:  # noqa: SIM110 - all() of a generator costs more here
            if module.physical_alarm_codes():
                return False
        return True

    def _module_cause(self, alarm: Alarm) -> bool:
        n = alarm.module
        return 0 < n <= len(self.bound) and self._answers(n) \
            and self.bound[n - 1].cause_present(alarm.code)

    def _latch(self, alarm: Alarm) -> None:
        """§7: the first alarm is the one reported; every module goes into alarm."""
        now = self.now_us
        self.alarm = alarm
        if alarm in self.edge_causes:
            self.edge_causes.remove(alarm)
        for module in self.modules():
            module.in_alarm = True
        info = alarm.info
        self.emit(AlarmChanged(now, self.device_id, code=fmt_hex(alarm.code, 2),
                               name=info.symbol, active=True, module=alarm.module))
        self.emit(EmergencySent(now, self.device_id, code=EMERGENCY_CODE,
                                register=EMERGENCY_REGISTER, data=alarm.data))
        frame = emergency_frame(EMERGENCY_CODE, EMERGENCY_REGISTER, alarm.data)
        self.mailbox = [*self.mailbox, frame][-MAILBOX_DEPTH:]
        code = alarm.al_status_code
        if code is not None and self.esm.state in (AlState.SAFEOP, AlState.OP):
            self.esm.fall(AlState.PREOP, code, now)  # §7.7: OP -> PREOP, 0x80XX

    def _try_reset(self, resync: bool) -> bool:
        """Reset fault (§6.17) or resync (§7): only a resettable alarm, only without cause."""
        alarm = self.alarm
        if alarm is None or (not resync and not alarm.resettable):
            return False
        if alarm in self._present_causes():
            return False
        self._clear_alarm()
        if alarm in self.raised:
            self.raised.remove(alarm)
        if alarm == Alarm(COUPLER, 0x12):
            self.address_fault = False
        if (alarm.table, alarm.code) == (COUPLER, 0x14):
            self.slot_fault = False  # checked again at the next PREOP -> SAFEOP
        return True

    def _clear_alarm(self) -> None:
        alarm, self.alarm = self.alarm, None
        self._quiet = False  # search in full from here
        for module in self.modules():
            module.in_alarm = False
        if alarm is not None:
            self.emit(AlarmChanged(self.now_us, self.device_id, code=fmt_hex(alarm.code, 2),
                                   name=alarm.info.symbol, active=False, module=alarm.module))

    def cmd_inject_fault(self, fault: str, module: int | None) -> None:
        alarm = self._fault(fault, module)
        if alarm.table == MODULE:
            self.check_module_fault(alarm.info.symbol, alarm.module)
        if alarm not in self.injected:
            self.injected.append(alarm)

    def cmd_clear_fault(self, fault: str, module: int | None) -> None:
        alarm = self._fault(fault, module)
        if alarm not in self.injected:
            now = ", ".join(f"{a.info.symbol}@{a.module}" for a in self.injected) or "none"
            raise CommandError(f"{alarm.info.symbol} on module {alarm.module} is not injected "
                               f"(injected: {now})")
        self.injected.remove(alarm)

    def _fault(self, fault: str, module: int | None) -> Alarm:
        row = parse_fault(fault)  # a module alarm without a module: RailMixin.check_command
        if module is not None and not 1 <= module <= MAX_MODULES:
            raise CommandError(f"module {module}: modules are numbered 1..{MAX_MODULES}")
        return Alarm(row.table, row.code, module or 0)

    def od_fault_active(self) -> bool:
        return self.alarm is not None

    def od_reset_fault(self) -> int:
        return self.reset_bit

    def od_set_reset_fault(self, value: int) -> None:
        rising = bool(value) and not self.reset_bit
        self.reset_bit = int(bool(value))
        if rising and self._try_reset(resync=False):  # §6.17: the rising edge resets
            self._evaluate_alarms()
            self._refresh()
        elif rising and self.alarm is not None:
            self._log_refused_reset(self.alarm)

    def _log_refused_reset(self, alarm: Alarm) -> None:
        """The device does nothing (§7); the log says the edge was taken and why it did not
        reset, as the servo drive logs "alarm reset refused" (a trainee saw no trace)."""
        why = ("not resettable (code above 0x7F): it needs a resync" if not alarm.resettable
               else "cause still present")
        where = f" module {alarm.module}" if alarm.module else ""
        self.emit(LogLine(self.now_us, self.device_id,
                          text=f"Reset fault refused: alarm {fmt_hex(alarm.code, 2)} "
                               f"{alarm.info.symbol}{where}, {why}"))

    def od_emergency_word(self) -> int:
        return self.alarm.word if self.alarm is not None else 0

    def describe_al_status_code(self, code: int) -> str:
        """The master's text for this coupler's AL status code: 0x80XX read as the State and
        Codes tabs read it (§7.7)."""
        return al_status_meaning(code)

