"""Application errors of the TRS-CAT: causes, their consequences, messages and emergencies.

Seed 001 §9.3.4 (every error shown in 0xF100 makes a 0x10F3 message) and §9.3.7 (the codes;
"Errore hardware interno" shuts the TRS bus down irreversibly while EtherCAT keeps running;
"Errore software interno" also sends the ESM back to PRE-OP, deadlocked). A cause is present
now (injected by an operator, or physical: field supply out of range, more than 8 A on the TRS
bus, an expansion unplugged under power, a refused slot configuration); a raised cause is one
alarm event, one diagnosis message and, with 0x10F3:5 bit 0, one CoE emergency. Irreversible
means until the logic supply is switched off. Cause -> code mapping: docs/trscat.md.
"""

from __future__ import annotations

import enum
from typing import TYPE_CHECKING

from devices.ethercat import AlState
from devices.events import AlarmChanged, EmergencySent, Event, LogLine, StateChanged, fmt_hex
from devices.trscat.diagnostics import (
    FAULTS,
    FLAG_EMERGENCY,
    AppFault,
    Bus,
    DiagHistory,
    DiagMessage,
    app_message,
    emergency_frame,
)
from devices.trscat.esm import MODULE_IDENT_MISMATCH, UNSPECIFIED_ERROR, Esm
from devices.trscat.io import BUS_MAX_A, SlotIo, field_in_range

if TYPE_CHECKING:
    from devices.trscat.catalog import ModuleKind
    from devices.trscat.sync import SyncUnit

FaultKey = tuple[str, int | None]  # (fault name, slot; None for the device-wide faults)
MAILBOX_DEPTH = 16  # emergencies kept for the master
TRS_BUS = "trs_bus"  # StateChanged.machine of the TRS bus
SUPPLY_FAULTS = frozenset({"FIELD_SUPPLY", "AN_PLUS_12V", "AN_MINUS_12V"})  # slot-level


class TrsBus(enum.Enum):
    OFF = "off"  # no logic supply
    DETECTING = "detecting"  # power-up: the configuration is read (§9.2 INIT); BUS LED off
    RUNNING = "running"  # BUS LED on (§8.2)
    SHUTDOWN = "shutdown"  # irreversible TRS bus error (§8.2, §9.3.7); BUS LED off


# Why every slot's outputs are off whatever the ESM's output mode: a bus not running services
# no module (§9.3.7: "a module the bus no longer services stops"). SHUTDOWN is latched: only
# the logic supply off and on ends it (§8.2 "irreversibile").
OUTPUTS_STOPPED_BY = {TrsBus.OFF: "node off", TrsBus.DETECTING: "bus detecting",
                      TrsBus.SHUTDOWN: "bus down"}


class AlarmsMixin:
    """Alarm handling of :class:`~devices.trscat.device.TrsCat`."""

    # Provided by TrsCat (declared for type checkers).
    device_id: str
    now_us: int
    powered: bool
    field_v: float
    bus: TrsBus
    rail: list[SlotIo | None]
    detected: list[ModuleKind]
    injected: list[FaultKey]
    active: dict[FaultKey, AppFault]
    shutdown: FaultKey | None
    deadlocked: bool
    config_error: int | None
    diag: DiagHistory
    mailbox: list[bytes]
    esm: Esm
    sync: SyncUnit

    if TYPE_CHECKING:  # defined by DeviceModel / TrsCat; stubs here would shadow them
        def emit(self, event: Event) -> None: ...
        def _leave_to(self, target: AlState) -> None: ...
        def _apply_output_image(self) -> None: ...

    # ---- causes -------------------------------------------------------------------------------
    def serviced(self, slot: int) -> bool:
        """The TRS bus exchanges data with the module in ``slot`` (detected and still there)."""
        io = self.rail[slot] if slot < len(self.rail) else None
        return self.bus is TrsBus.RUNNING and slot < len(self.detected) and io is not None \
            and io.kind is self.detected[slot]

    def bus_current_a(self) -> float:
        return sum(io.field_current_a() for s, io in enumerate(self.rail)
                   if io is not None and self.serviced(s))

    def _present_causes(self) -> list[FaultKey]:
        causes: list[FaultKey] = list(self.injected)
        if not field_in_range(self.field_v):
            causes.append(("FIELD_SUPPLY", 0))
        if self.bus is TrsBus.RUNNING:
            if self.bus_current_a() > BUS_MAX_A:
                causes.append(("TRS_OVERCURRENT", None))
            if any(not self.serviced(s) for s in range(len(self.detected))):
                causes.append(("TRS_COMM_ERROR", None))  # §7: unplugged under power
        if self.config_error is not None:
            causes.append(("CONFIG_ERROR", self.config_error))
        if self.shutdown is not None:
            causes.append(self.shutdown)  # irreversible: stays until power-off
        if self.deadlocked:
            causes.append(("SOFTWARE_ERROR", None))
        return list(dict.fromkeys(causes))

    def slot_fault(self, slot: int, names: frozenset[str] = SUPPLY_FAULTS) -> bool:
        return any(name in names and s == slot for name, s in self.active)

    def _evaluate_alarms(self) -> None:
        if not self.powered or self.bus in (TrsBus.OFF, TrsBus.DETECTING):
            return
        causes = self._present_causes()
        for key in causes:
            if key not in self.active:
                self._raise(key)
        for key in [k for k in self.active if k not in causes]:
            self._clear(key)

    # ---- raising and clearing -----------------------------------------------------------------
    def _raise(self, key: FaultKey) -> None:
        name, slot = key
        fault = FAULTS[name]
        self.active[key] = fault
        self.emit(AlarmChanged(self.now_us, self.device_id, code=fmt_hex(fault.code, 4),
                               name=name, active=True, module=slot or 0))
        self.report(app_message(fault, slot, self.now_us * 1000), fault, slot)
        if fault.bus_shutdown and self.shutdown is None and self.bus is TrsBus.RUNNING:
            self.shutdown = key
            self._set_bus(TrsBus.SHUTDOWN)
            self._log(f"TRS bus shut down: 0x{fault.code:04X} {fault.text}")
            # Every module stops now, not at the next local cycle: in DC-SYNC none comes
            # while SYNC0 is lost or switched off (§9.1.1), and held outputs would stay on.
            self._apply_output_image()
        if fault.deadlock and not self.deadlocked:
            self.deadlocked = True
            self._log("internal software error: back to PRE-OP, deadlock until power-off")
            target = AlState.PREOP if self.esm.state in (AlState.SAFEOP, AlState.OP) \
                else self.esm.state
            self._leave_to(target)
            self.esm.fall(target, UNSPECIFIED_ERROR, self.now_us)
        elif fault.config_check and self.esm.state in (AlState.SAFEOP, AlState.OP):
            # Only an injection raises it above PRE-OP (the real check runs at PS): show it
            # as the device would after that check, not as a silent alarm in OP.
            self._leave_to(AlState.PREOP)
            self.esm.fall(AlState.PREOP, MODULE_IDENT_MISMATCH, self.now_us)

    def _clear(self, key: FaultKey) -> None:
        fault = self.active.pop(key)
        name, slot = key
        self.emit(AlarmChanged(self.now_us, self.device_id, code=fmt_hex(fault.code, 4),
                               name=name, active=False, module=slot or 0))

    def clear_all_alarms(self) -> None:
        for key in list(self.active):
            self._clear(key)

    def report(self, message: DiagMessage, fault: AppFault | None = None,
               slot: int | None = None) -> None:
        """A new 0x10F3 message (§9.3.7); with 0x10F3:5 bit 0 an application error is also
        sent as a CoE emergency (ETG.1020)."""
        stored = self.diag.add(message)
        if not stored or fault is None or not self.diag.flags & FLAG_EMERGENCY:
            return
        frame = emergency_frame(fault, slot, self.od_error_register())
        self.mailbox = [*self.mailbox, frame][-MAILBOX_DEPTH:]
        self.emit(EmergencySent(self.now_us, self.device_id, code=fault.code,
                                register=frame[2], data=frame[3:]))

    def _set_bus(self, state: TrsBus) -> None:
        if state is not self.bus:
            self.emit(StateChanged(self.now_us, self.device_id, from_state=self.bus.value,
                                   to_state=state.value, machine=TRS_BUS))
            self.bus = state

    def _log(self, text: str) -> None:
        self.emit(LogLine(self.now_us, self.device_id, text=text))

    # ---- 0xF100 and 0x1001 --------------------------------------------------------------------
    def od_diag_status(self) -> int:
        """§9.3.4 0xF100:1: bit s = slot s working (1) or in error / not configured (0)."""
        bits = 0
        for slot in range(len(self.detected)):
            if self.serviced(slot) and not self.slot_fault(slot):
                bits |= 1 << slot
        return bits

    def od_bus_ok(self, sub: int) -> bool:
        """§9.3.4 0xF100:2..4 (TRUE = OK): FALSE while a fault of that kind is active. The one
        that shut the bus stays active until power-off (irreversible); one raised with the
        bus already down, which only an injection can, shows too, as its message does."""
        flag = {2: Bus.COMMUNICATION, 3: Bus.VOLTAGE, 4: Bus.CURRENT}[sub]
        return all(fault.bus_flag is not flag for fault in self.active.values())

    def od_error_register(self) -> int:
        """DS301 0x1001: the error register bits of the active errors."""
        out = 0
        for fault in self.active.values():
            out |= fault.register
        return out
