"""The TRS-CAT remote I/O (seed 001): logic supply, TRS bus, ESM, sync, I/O, LEDs, snapshot.

Slot 0 is the integrated module (16 bidirectional lines), slots 1..7 the TRS-nn-E expansions
in bus order. At power-up the device reads the TRS bus configuration (0xF050, §9.2 INIT); the
master writes 0xF030 in PRE-OP and the PREOP -> SAFEOP transition compares them (§9.3.2).
Local cycles (sampling, debounce, outputs) run on SYNC0 in DC-SYNC or every 500 us in
FREE-RUN (devices/trscat/sync.py). A communication error in OP sends the device to SAFE-OP
with the error flag, its outputs following 0xF700 / 0xF701 / 0xF710 (devices/trscat/outputs.py).
Behaviour and choices: docs/trscat.md.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from devices.device import Action, DeviceModel
from devices.esm import AlStatusView, CoeMailbox, first_refusal
from devices.ethercat import AlState
from devices.leds import LedBank
from devices.od import AbortCode, ObjectDictionary, SdoAbort, TypeNames
from devices.sync_managers import SmSetup
from devices.trscat.alarms import OUTPUTS_STOPPED_BY, AlarmsMixin, FaultKey, TrsBus
from devices.trscat.catalog import (
    BY_IDENT,
    INTEGRATED,
    MAX_SLOTS,
    ModuleKind,
    expansion_list,
    ident_allowed_at,
)
from devices.trscat.commands import ACTIONS, CommandsMixin
from devices.trscat.diagnostics import AppFault, DiagHistory
from devices.trscat.esm import TRANSITION_CHECKS, Esm
from devices.trscat.indicators import LedInputs
from devices.trscat.io import SlotIo
from devices.trscat.module_checks import ModuleChecks
from devices.trscat.objects import TYPE_NAMES, build_od, refuse_in_state
from devices.trscat.pdo import outputs_index
from devices.trscat.sm_checks import SmChecksMixin, SmKey
from devices.trscat.spans import SpansMixin
from devices.trscat.stepping import SteppingMixin
from devices.trscat.sync import MODE_BY_NAME, SyncUnit
from devices.trscat.transitions import OutputMode, TransitionsMixin

DETECT_BASE_US = 200_000  # FieldRig: power-up until the TRS bus scan starts
DETECT_PER_SLOT_US = 50_000  # FieldRig: per slot read on the TRS bus
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_LATCHING = (AlState.SAFEOP, AlState.OP)  # the states in which a frame latches the outputs


class TrsCat(SpansMixin, SteppingMixin, TransitionsMixin, SmChecksMixin, AlarmsMixin, ModuleChecks,
             CommandsMixin, CoeMailbox, AlStatusView, DeviceModel):
    KIND = "trscat"
    QUIET_SNAPSHOT = True  # tests/hardening/test_revision.py
    ACTIONS: ClassVar[Mapping[str, Action]] = ACTIONS
    TYPE_NAMES: ClassVar[TypeNames] = TYPE_NAMES  # seed 001 §9.3's U8, U16, U32, Bool

    def __init__(self, device_id: str, rng: random.Random, expansions: Sequence[str] = (),
                 sync_mode: str = "dc",
                 field_supply_v: float = 24.0, out_link: bool = False,
                 box_name: str = "Box 2 (TRS-CAT)", station_address: int = 1002) -> None:
        super().__init__(device_id=device_id, rng=rng)
        self._still_state()
        kinds = expansion_list(expansions, "expansion")
        if str(sync_mode).lower() not in MODE_BY_NAME:
            raise ValueError(f"sync_mode {sync_mode!r}: the TRS-CAT runs 'dc' (DC-SYNC, "
                             f"default) or 'free_run' (seed 001 §9.1.1)")
        if not 0.0 <= float(field_supply_v) <= 40.0:
            raise ValueError(f"field_supply_v {field_supply_v}: give 0..40 V (24 V nominal, "
                             f"seed 001 §3)")
        # The mode the line's master is set up for (§9.3 "opzioni da settare nel master"): the
        # built-in master activates SYNC0 for it or not (app/network/files.py uses_dc). The
        # device itself takes its mode from the Sync Control register at PS (§9.1.1).
        self.master_sync_mode = MODE_BY_NAME[str(sync_mode).lower()]
        self.rail: list[SlotIo | None] = [SlotIo.new(INTEGRATED),
                                          *(SlotIo.new(k) for k in kinds)]
        self.box_name = box_name
        self.station_address = station_address
        self.serial = self.rng.getrandbits(32)
        # Each port's link: the cable the line gives it (line_in / line_out, the master's
        # set_link) and the operator's own plug at the port (plugs: IN, OUT; the master
        # folds them into its line model). Kept apart, so neither undoes the other.
        self.plugs = (True, True)
        self.line_in, self.line_out = True, out_link
        self.link_in, self.link_out = True, out_link
        self.field_v = float(field_supply_v)
        self.injected: list[FaultKey] = []
        self.injected_sm: list[SmKey] = []
        self.sm_setup: tuple[SmSetup, ...] | None = None  # a master on the wire wrote them
        self.esm = Esm(self.emit, device_id, stop_mailbox=self._stop_mailbox,
                       leave_op=self._leave_op)
        self.leds = LedBank(device_id)
        self._led_inputs: LedInputs | None = None
        self.powered = False
        self.bus = TrsBus.OFF
        self._power_up_state()
        self.cmd_power(True)

    def _power_up_state(self) -> None:
        """Everything volatile, as the logic supply comes (or goes)."""
        self.detect_done_us = 0
        self.detected: list[ModuleKind] = []
        self.f030 = [1, INTEGRATED.ident] + [0] * (MAX_SLOTS - 1)  # §9.3.2 defaults
        self.f050 = [0] * (MAX_SLOTS + 1)
        self.error_values = [0] * MAX_SLOTS  # §9.3.5: 0 at reset
        self.error_modes = [0] * MAX_SLOTS
        self.sysok_mask = 0  # §9.3.6: 0 at reset
        self.sync = SyncUnit(next_free_us=self.now_us)  # DC-SYNC, the §9.1.1 default
        self.sync_state = self.sync.state
        self.diag = DiagHistory()
        self.active: dict[FaultKey, AppFault] = {}
        self.shutdown: FaultKey | None = None
        self.deadlocked = False
        self.config_error: int | None = None
        self.out_mode = OutputMode.SAFE
        self.error_out: dict[int, list[int]] = {}
        self.last_sm_event_us: int | None = None
        self.last_frame_us: int | None = None
        self.mailbox: list[bytes] = []
        self.od: ObjectDictionary | None = None
        for io in self.rail:
            if io is not None:
                io.reset()

    def cmd_power(self, on: bool) -> None:
        self._touch()
        if on == self.powered:
            return
        self.clear_all_alarms()
        self.powered = on
        was = self.sync_state
        self._power_up_state()
        self.sync_state = was  # the new sync unit's state is a change like any other (event)
        if on:
            slots = 1 + len(self._chain())
            self.detect_done_us = self.now_us + DETECT_BASE_US + DETECT_PER_SLOT_US * slots
            self._set_bus(TrsBus.DETECTING)
        else:
            self.esm.reset(self.now_us)
            self._set_bus(TrsBus.OFF)
        self._sync_event()
        self._refresh()

    def _chain(self) -> list[ModuleKind]:
        """The expansions the TRS bus reaches: in order, up to the first empty position."""
        out = []
        for io in self.rail[1:]:
            if io is None:
                break
            out.append(io.kind)
        return out

    # ---- the master's side ----------------------------------------------------------------
    def reachable(self) -> bool:
        return self.powered and self.link_in

    def exchange_frame(self, now_us: int) -> None:
        """One process-data frame of the master passed through (an SM2 event)."""
        if not (self.powered and self.link_in):  # reachable(), inlined: called every cycle
            return
        self.last_frame_us = now_us
        if self.sync.frame(now_us, self.rng) and self.esm.state in _LATCHING:
            self._latch_outputs(now_us)

    def take_emergencies(self) -> list[bytes]:
        """8-byte CoE emergencies in the mailbox; it runs from PRE-OP on. An empty mailbox
        answers at once (every cycle; the mailbox is only ever replaced, never appended to)."""
        if not self.mailbox or not (self.powered and self.link_in) or \
                self.esm.state is AlState.INIT:
            return []
        out, self.mailbox = self.mailbox, []
        return out

    def _stop_mailbox(self) -> None:
        """Any state -> INIT (devices/esm.py): the emergencies not read yet are lost; the
        0x10F3 history keeps its messages."""
        self.mailbox = []

    def read_object(self, index: int, sub: int) -> Any:
        """SDO upload (raises SdoAbort with the DS301 code)."""
        return self.require_od().read(index, sub)

    def write_object(self, index: int, sub: int, value: Any) -> None:
        """SDO download (raises SdoAbort with the DS301 code)."""
        self._touch()
        self.require_od().write(index, sub, value)
        self._refresh()

    def set_link(self, connected: bool, port: str = "in") -> None:
        """A cable on port IN (from the master's side) or OUT (to the next slave)."""
        self._touch()
        if port == "in":
            self.line_in = connected
        else:
            self.line_out = connected
        self._ports()
        self._refresh()

    def _ports(self) -> None:
        """Each port's link: the line's cable there and the slave's own plug."""
        self.link_in = self.line_in and self.plugs[0]
        self.link_out = self.line_out and self.plugs[1]

    def set_power(self, on: bool) -> None:
        self.cmd_power(on)

    def mailbox_write(self, index: int, sub: int, value: Any) -> None:
        self.write_object(index, sub, value)  # a master's SDO download: touched and refreshed

    def configure_dc(self, activation: int, sync0_cycle_ns: int, start_time_ns: int) -> None:
        """The master wrote the ESC's DC registers: 0x0981 activation (the Sync Control
        register's high byte), 0x09A0 SYNC0 cycle (ns), 0x0990 SYNC0 start time (ns of the DC
        system time). PREOP -> SAFEOP takes the mode from them and, in DC-SYNC, SYNC0 runs on
        them (§9.1.1; 0x1C32:1 / :2 then show the mode and the cycle, §9.3.1)."""
        if not self.powered:
            return  # the ESC is off: nothing to write into
        self._touch()
        self.sync.configure(activation, sync0_cycle_ns, start_time_ns, self.now_us)
        self._refresh()

    def set_dc_fault(self, kind: str | None) -> None:
        """The master's DC faults as this device sees them (§9.1.1, §9.3.7): ``jitter``
        makes each frame arrive up to a cycle late (SM events missed, sync error),
        ``sync0_lost`` stops SYNC0 (fatal sync error); ``drift`` and None clear both."""
        self._touch()
        self.sync.jitter_us = self.sync.cycle_us if kind == "jitter" else 0
        self.sync.sync0_lost = kind == "sync0_lost"

    # ---- stepping: devices/trscat/stepping.py ------------------------------------------------
    def _finish_detection(self) -> None:
        self.detected = [INTEGRATED, *self._chain()]
        self.f050 = [len(self.detected), *(k.ident for k in self.detected)]
        self.f050 += [0] * (MAX_SLOTS + 1 - len(self.f050))
        self._set_bus(TrsBus.RUNNING)
        self._rebuild_od()
        if self.esm.state is AlState.INIT and self.esm.requested is AlState.PREOP:
            code = first_refusal(self, TRANSITION_CHECKS, AlState.INIT, AlState.PREOP)
            if code is None:
                self._enter(AlState.PREOP)
            else:
                self.esm.refuse(code, self.now_us)

    # ---- object dictionary ------------------------------------------------------------------
    def _rebuild_od(self) -> None:
        configured = [BY_IDENT.get(self.f030[s]) for s in range(1, self.f030[0] + 1)]
        self.od = build_od(self, configured, self.detected, self._touch)

    def od_write_f030(self, sub: int, value: int) -> None:
        """§9.3.2: written by the master in PRE-OP only; the PDO assignment follows."""
        if self.esm.state is not AlState.PREOP:
            raise refuse_in_state(0xF030, sub)
        # 0 = an unused expansion position; sub 1 (the integrated module) admits only its
        # own ident, "ammesso solo 0x494F2D42".
        unused = sub >= 2 and value == 0
        if sub > 0 and not unused and not ident_allowed_at(sub, value):
            raise SdoAbort(AbortCode.VALUE_RANGE, 0xF030, sub)
        self.f030[sub] = value
        self._rebuild_od()

    def od_acknowledge(self, value: int) -> None:
        self.diag.acknowledge(int(value))

    def od_input(self, slot: int, channel: int) -> int:
        io = self.rail[slot] if slot < len(self.rail) else None
        return io.inputs[channel] if io is not None and io.kind is self.detected[slot] else 0

    def od_output(self, slot: int, channel: int) -> int:
        io = self.rail[slot] if slot < len(self.rail) else None
        return io.plc[channel] if io is not None and io.kind is self.detected[slot] else 0

    def od_write_output(self, slot: int, channel: int, value: int) -> None:
        """0x7ss0 written: the objects are the detected module's; with that module gone (or
        another one in its place) the write has nowhere to go, as a read gives 0."""
        io = self.rail[slot] if slot < len(self.rail) else None
        if io is None or io.kind is not self.detected[slot]:
            raise SdoAbort(AbortCode.CANNOT_STORE, outputs_index(slot), channel + 1)
        self.od_set_output(slot, channel, value)

    # ---- what the outside sees --------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        sync = self.sync
        return {
            "kind": self.KIND, "id": self.device_id, "powered": self.powered,
            "esm": self.esm.state.label, "requested": self.esm.requested.label,
            "al_status": self.esm.register, "al_status_code": self.esm.code,
            "box_name": self.box_name, "station_address": self.station_address,
            "leds": self.leds.snapshot(),
            "links": {"in": self.link_in, "out": self.link_out},
            # the base's terminals as a meter reads them: 0 V while 0x3220 is injected there
            # (the supply failing, docs/trscat.md), not the value last set
            "field_supply_v": self._slot_field_v(0), "field_ok": self.field_ok(),
            "trs_bus": {"state": self.bus.value, "latched": self.bus is TrsBus.SHUTDOWN,
                        "current_a": round(self.bus_current_a(), 3),
                        "communication_ok": self.od_bus_ok(2), "voltage_ok": self.od_bus_ok(3),
                        "current_ok": self.od_bus_ok(4)},
            "sync": {"mode": sync.mode.label, "sync_control": sync.sync_control,
                     "state": sync.state.value, "cycle_ns": sync.cycle_ns,
                     "sm_event_missed": sync.sm_missed, "sync_error": sync.sync_error,
                     "sync0_lost": sync.sync0_lost, "jitter_us": sync.jitter_us,
                     "dc_activation": sync.dc_activation, "sync0_cycle_ns": sync.dc_cycle_ns,
                     "sync0_start_ns": sync.dc_start_ns},
            "outputs_mode": self.out_mode.value, "deadlocked": self.deadlocked,
            "outputs_stopped": OUTPUTS_STOPPED_BY.get(self.bus),
            "f030": list(self.f030), "f050": list(self.f050),
            "diag_status": self.od_diag_status() if self.detected else 0,
            "error_values": list(self.error_values), "error_modes": list(self.error_modes),
            "sysok_mask": self.sysok_mask,
            "slots": [self._slot_snapshot(s, io) for s, io in enumerate(self.rail)],
            "alarms": [{"code": f"0x{f.code:04X}", "name": name, "slot": slot}
                       for (name, slot), f in self.active.items()],
            "injected": [{"fault": name, "slot": slot} for name, slot in self.injected],
            "injected_sm": [{"fault": name, "sm": sm} for name, sm in self.injected_sm],
            "diagnosis": self.diag.snapshot(),
        }

    def _slot_snapshot(self, slot: int, io: SlotIo | None) -> dict[str, Any]:
        if io is None:
            # An empty position: what the master's 0xF030 names there (None while nothing
            # was written there), so a view can name the module that is missing.
            kind = BY_IDENT.get(self.f030[slot + 1]) if slot < self.f030[0] else None
            return {"slot": slot, "type": None,
                    "configured": kind.name if kind is not None else None}
        detected = self.detected[slot].name if slot < len(self.detected) else None
        return {"slot": slot, "type": io.kind.name, "ident": f"0x{io.kind.ident:08X}",
                "detected_as": detected, "serviced": self.serviced(slot),
                **io.snapshot()}
