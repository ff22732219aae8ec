"""The Festo CPX-E-EC bus module (seed 002): supplies, switches, ESM, process data, diagnosis.

One model for the bus module and the CPX-E I/O modules behind it. The built-in master drives
it through the Slave protocol of devices/master.py (``request_state``, ``exchange_frame``,
``take_emergencies``, ...); a master's CoE access, the scenario and the dashboard go through
``write_object`` / ``read_object``. What the seed leaves open, and why the model does what it
does, is in docs/cpx-e-ec.md.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from devices.cpx.actions import ACTIONS, OperatorMixin
from devices.cpx.addressing import AddressSpace, assign_addresses, check_configuration
from devices.cpx.assignment import address_order, tx_assignment
from devices.cpx.catalog import ModuleType, module_type
from devices.cpx.device_id import DeviceIdMixin
from devices.cpx.diagnosis import Diagnosis
from devices.cpx.esm import NO_VALID_FIRMWARE, SM_WATCHDOG, SYNC_ERROR, ErrorKind, Esm
from devices.cpx.faults import Injected, held
from devices.cpx.history import DiagHistory
from devices.cpx.indicators import wanted_leds
from devices.cpx.leds import LedBank
from devices.cpx.module_checks import ModuleChecks
from devices.cpx.modules import CpxModule, ModuleFault, Monitors, held_off
from devices.cpx.objects import SYNC_ERROR_COUNTER_LIMIT, TYPE_NAMES, build_od
from devices.cpx.stillness import StillStepping
from devices.cpx.switches import BUS_MODULE, DiagMode, Switches, check_rotary
from devices.cpx.transitions import WATCHDOG_US, TransitionsMixin
from devices.cpx.unseen import undiagnosed
from devices.device import Action, DeviceModel
from devices.esm import NO_COE_STATES, AlStatusView, CoeMailbox
from devices.ethercat import AlState, sync_error_reached
from devices.events import LogLine
from devices.od import ObjectDictionary, TypeNames

SUPPLY_NOMINAL_V = 24.0  # Tab. 29: U_EL/SEN 24 V DC +- 25 %
SUPPLY_MIN_V = 18.0  # ... below this: undervoltage (FieldRig uses the same band for U_OUT)
BROWNOUT_V = 10.0  # FieldRig: the electronics stop below this
# FieldRig: an injected undervoltage is its supply sagged to this, below Tab. 29's 18 V and
# above BROWNOUT_V, so the bus module keeps running to report it (docs/cpx-e-ec.md choice 27)
INJECTED_SAG_V = 17.0
BRIDGING_US = 20_000  # Tab. 29: mains buffering time 20 ms
ACTIVITY_WINDOW_US = 50_000  # LA IN / LA OUT flicker while frames passed this recently
SYNC_MISSED_STEP = 3  # ETG.1020 sync error counter: +3 per missed event, -1 per good one
SYNC_COUNTER_CAP = SYNC_ERROR_COUNTER_LIMIT + SYNC_MISSED_STEP  # recovers in a few cycles
PD_STATES = frozenset({AlState.SAFEOP, AlState.OP})  # the sync error counter counts
QUIET_HORIZON_STEPS = 1 << 40  # a quiet span with no clock comparison left to flip: "forever"
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_BOOTLOADER = DiagMode.BOOTLOADER


class CpxEEc(StillStepping, TransitionsMixin, DeviceIdMixin, ModuleChecks, OperatorMixin,
             CoeMailbox, AlStatusView, DeviceModel):
    KIND = "cpx_e_ec"
    QUIET_SNAPSHOT = True  # tests/hardening/test_revision.py
    ACTIONS: ClassVar[Mapping[str, Action]] = ACTIONS
    TYPE_NAMES: ClassVar[TypeNames] = TYPE_NAMES  # seed 002 Tab. 27's U8, U32, BYTE[23] ...

    def __init__(self, device_id: str, rng: random.Random,
                 modules: Sequence[str | tuple[str, Mapping[str, Any]]] = (),
                 rotary_switch: int = 0, dil1: bool = False, dil2: bool = False,
                 out_connected: bool = False,
                 box_name: str = "Box 3 (CPX-E-EC)", station_address: int = 1003) -> None:
        super().__init__(device_id=device_id, rng=rng)
        self._init_still()
        self.modules: list[CpxModule] = []
        for number, item in enumerate(modules, start=1):
            name, options = (item, {}) if isinstance(item, str) else item
            try:
                mtype = module_type(name)
                self.modules.append(CpxModule.build(number, mtype, options or {}))
            except (KeyError, ValueError) as exc:
                raise ValueError(f"module {number}: {exc.args[0]}") from None
        self.switches = Switches(check_rotary(rotary_switch), dil1, dil2)
        check_configuration(BUS_MODULE[self.switches.mode], [m.mtype for m in self.modules])
        self.box_name = box_name
        self.station_address = station_address
        self.serial = self.rng.getrandbits(32)
        self.default_ranges = [list(m.ranges) for m in self.modules]
        self.el_sen_v = 0.0
        self.out_v = SUPPLY_NOMINAL_V
        # Each port's link: the cable the line gives it (line_in / line_out, the master's
        # set_link) and the operator's own plug at the port (plugs: IN, OUT; the master
        # folds them into its line model). Kept apart, so neither undoes the other.
        self.plugs = (True, True)
        self.line_in, self.line_out = True, out_connected
        self.link_in, self.link_out = True, out_connected
        self.injected: list[Injected] = []
        self.fault_names: frozenset[str] = frozenset()
        # A request refused in OP goes to SAFEOP (devices/esm.py Esm.leave_op): the outputs
        # follow the ESM at the next step (_output_values, 0x2400:7), as after OP -> SAFEOP.
        self.esm = Esm(self.emit, device_id, stop_mailbox=self._stop_mailbox,
                       leave_op=self.touch)
        self.leds = LedBank(device_id)
        self.powered = False
        self.low_since_us: int | None = None
        self._clear_runtime()
        self.cmd_power(True)

    # ---- power, start ---------------------------------------------------------------------
    def _clear_runtime(self) -> None:
        self.bus = CpxModule(0, BUS_MODULE[self.switches.active_mode])
        self.units: list[CpxModule] = [self.bus, *self.modules]
        self.sti_request = 0  # the I/O diagnostic interface's request word taken last in OP
        # 0x1C13 (RAM): the default at every start, written by a master in PREOP only
        self.tx_assign = tx_assignment(address_order(self.units, receive=False),
                                       lambda: self.esm.state is AlState.PREOP)
        # 0x10F3:5 at Tab. 14's 0x0000 at every start: only a master's write sets it (the
        # built-in master's PS init command from the rig's history_flags, choice 19)
        self.history = DiagHistory()
        self.diagnosis = Diagnosis(self.device_id, self.emit, self.history,
                                   self._filter_no_error, self._reports_errors)
        self.od: ObjectDictionary | None = None
        self.space: AddressSpace | None = None
        self.space_error: str = ""
        self.f030_written = False
        self.boot_failed = False
        self.power_on_us = self.now_us
        self.last_frame_us: int | None = None
        self.last_pd_us = self.now_us
        self.sync_counter = 0
        self.id_requested = False

    def _start(self) -> None:
        """Power-up or restart: switches and modules read, dictionary built, INIT (§2.1.7)."""
        self.switches.read_at_start()
        self.power_ups += 1
        self._clear_runtime()
        for module, ranges in zip(self.modules, self.default_ranges, strict=True):
            module.reset(ranges)
        try:
            self.space = check_configuration(self.bus.mtype, [m.mtype for m in self.modules])
        except ValueError as exc:  # a DIL change can push the terminal past 64 bytes
            self.space_error = str(exc)
            self.emit(LogLine(self.now_us, self.device_id, text=self.space_error))
            self.space = AddressSpace.of(self.bus.mtype, [m.mtype for m in self.modules])
        self.boot_failed = self.has_fault("booting_error")
        self.od = build_od(self)
        self._announce_writes(self.od)
        self.esm.reset(self.now_us)
        if self.boot_failed:  # ETG.1300 booting error: INIT with the error bit, unasked
            self.esm.fall(AlState.INIT, ErrorKind.BOOTING, NO_VALID_FIRMWARE, self.now_us)

    def _stop(self) -> None:
        self.diagnosis.halt(self.now_us)
        self._outputs_dead()
        self.esm.reset(self.now_us)
        self._clear_runtime()

    def _set_powered(self, on: bool) -> None:
        if on == self.powered:
            return
        self.powered = on
        if on:
            self._start()
        else:
            self._stop()
        self._refresh_leds()

    @property
    def application_runs(self) -> bool:
        """The application controller runs the CPX-E system (not bootloader, not failed)."""
        return self.powered and not self.boot_failed and not self.has_fault("ac_failure") and \
            self.switches.active_mode is not DiagMode.BOOTLOADER

    # ---- the master's side ----------------------------------------------------------------
    @property
    def explicit_device_id(self) -> int:
        return self.switches.explicit_device_id if self.powered else 0

    def reachable(self) -> bool:
        return self.powered and self.link_in

    def mailbox_runs(self) -> bool:
        # Tab. 12 red on: the application controller, which runs CoE, does not answer; the
        # ESC still passes frames (docs/cpx-e-ec.md choice 25)
        return not self.has_fault("ac_failure")

    def exchange_frame(self, now_us: int) -> None:  # no touch: stillness.clock_key
        """One process-data cycle of the master passed through this slave."""
        # reachable(), has_fault() and application_runs inline: the master calls this every
        # cycle (docs/cpx-e-ec.md "Step cost")
        if not (self.powered and self.link_in):
            return
        self.last_frame_us = now_us
        faults = self.fault_names
        if "watchdog" in faults or not (
                self.powered and not self.boot_failed and "ac_failure" not in faults
                and self.switches.active_mode is not _BOOTLOADER):
            return  # the frame passes the ESC, but no process data reach the application
        self.last_pd_us = now_us
        if self.esm.state in PD_STATES:
            counter = self.sync_counter
            if "sync_error" in faults:
                self.sync_counter = min(SYNC_COUNTER_CAP, counter + SYNC_MISSED_STEP)
            elif counter > 0:
                self.sync_counter = counter - 1
            else:
                self.sync_counter = 0  # max(0, counter - 1)

    def frames_quiet(self) -> bool:
        """Would the master's frames, one now and one per cycle while this slave's own steps
        stay quiet (:meth:`quiet_until`), change nothing but what :meth:`skip_frames` sets?
        (docs/cpx-e-ec.md "Quiet spans"). Ask it with :meth:`quiet_until`, before the span.

        A frame sets ``last_frame_us`` / ``last_pd_us`` and steps ``sync_counter``; the steps
        read them only through the clock key's comparisons (traffic, "no master", the SM
        watchdog, the sync error). Frames make the first two fresher, so those comparisons
        keep their frameless value when that is already "traffic, a master, process data":
        quiet_until ends the span before the frameless value could flip. The counter goes
        down to 0 (or up to its cap with a sync fault) without crossing the limit when it is
        on the side it goes to. The master's take_emergencies, every cycle, hands nothing
        over while the mailbox is empty (quiet steps queue nothing)."""
        if not (self.powered and self.link_in):
            return True  # exchange_frame returns at once
        if self.diagnosis.mailbox and self.esm.state not in NO_COE_STATES:
            return False  # the cycle's take_emergencies would hand them over (and touch)
        step = self._still.dt
        if not step:
            return False  # no still step proved: quiet_until gives no span either
        first, last = self.now_us + step, self.last_frame_us  # the span's first step
        if last is None or first - last > ACTIVITY_WINDOW_US:
            return False  # a frame would light LA IN / LA OUT and end "no master"
        faults = self.fault_names
        if "watchdog" in faults or not (
                not self.boot_failed and "ac_failure" not in faults
                and self.switches.active_mode is not DiagMode.BOOTLOADER):
            return True  # process data do not reach the application: only last_frame_us
        if first - self.last_pd_us > WATCHDOG_US:
            return False  # process data again would end the SM watchdog's expiry
        if self.esm.state in PD_STATES:
            return self.sync_error() == ("sync_error" in faults)
        return True

    def skip_frames(self, n: int, last_us: int) -> None:
        """As ``n`` calls of :meth:`exchange_frame`, one per master cycle, the last at
        ``last_us``, while :meth:`frames_quiet` holds (nothing they read changes between)."""
        if n <= 0 or not (self.powered and self.link_in):
            return
        self.last_frame_us = last_us
        faults = self.fault_names
        if "watchdog" in faults or not (
                not self.boot_failed and "ac_failure" not in faults
                and self.switches.active_mode is not DiagMode.BOOTLOADER):
            return
        self.last_pd_us = last_us
        if self.esm.state in PD_STATES:
            if "sync_error" in faults:
                self.sync_counter = min(SYNC_COUNTER_CAP, self.sync_counter + SYNC_MISSED_STEP * n)
            else:
                self.sync_counter = max(0, self.sync_counter - n)

    def take_emergencies(self) -> list[bytes]:
        """8-byte emergencies (§2.5.3) queued in the mailbox; it runs from PREOP on."""
        if not self.diagnosis.mailbox:  # the master asks every cycle: nothing to hand over
            return []
        if not self.reachable() or not self.mailbox_runs() or self.esm.state in NO_COE_STATES:
            return []  # emergencies are CoE: none in BOOT either (choice 47)
        out, self.diagnosis.mailbox = self.diagnosis.mailbox, []
        if out:
            self.touch()
        return out

    def _stop_mailbox(self) -> None:
        """Any state -> INIT (devices/esm.py): the emergencies not read yet are lost; the
        0x10F3 history keeps its messages."""
        self.diagnosis.mailbox = []

    def set_link(self, connected: bool, port: str = "in") -> None:
        """A cable on port X1 (IN, from the master's side) or X2 (OUT)."""
        self.touch()
        if port == "in":
            self.line_in = connected
        else:
            self.line_out = connected
        self._ports()

    def _ports(self) -> None:
        """Each port's link: the line's cable there and the slave's own plug."""
        self.link_in = self.line_in and self.plugs[0]
        self.link_out = self.line_out and self.plugs[1]

    def set_power(self, on: bool) -> None:
        self.touch()
        self.cmd_power(on)

    def set_dc_fault(self, kind: str | None) -> None:
        """The master's DC faults as the bus module sees them: jitter or lost SYNC0 are
        missed sync events (the "sync_error" fault, Tab. 12); drift and None clear it."""
        self.touch()
        entry = Injected("sync_error")
        if kind in ("jitter", "sync0_lost") and entry not in self.injected:
            self.injected.append(entry)
        elif kind not in ("jitter", "sync0_lost") and entry in self.injected:
            self.injected.remove(entry)
        self.faults_changed()

    # ---- stepping (skipping still steps: StillStepping, devices/cpx/stillness.py) -------
    def _full_step(self, dt_us: int) -> None:
        self._follow_supply()
        if not self.powered:
            return
        for module in self.modules:
            module.step(dt_us)
        if self.application_runs:
            self._supervise()
            self._process_data()
            self._diagnose()
        else:
            self._outputs_dead()
            if self.diagnosis.active:  # the application stopped under them (AC failure)
                self.diagnosis.halt(self.now_us)
        self._refresh_leds()

    def _outputs_dead(self) -> None:
        """No application (or no power): the modules get no output data, all switch off."""
        for module in self.modules:
            module.drive_outputs([0] * len(module.out_values), supply_ok=False)

    def _follow_supply(self) -> None:
        """U_EL/SEN: the electronics ride through dips shorter than 20 ms (Tab. 29)."""
        alive = self.u_el_sen_v >= BROWNOUT_V
        if alive:
            self.low_since_us = None
            self._set_powered(True)
            return
        if not self.powered:
            return
        if self.low_since_us is None:
            self.low_since_us = self.now_us
        if self.bridging_over():
            self._set_powered(False)

    def bridging_over(self) -> bool:
        return self.low_since_us is not None and self.now_us - self.low_since_us >= BRIDGING_US

    def pd_watchdog_expired(self) -> bool:
        """No process data for the Sync Manager watchdog time."""
        return self.now_us - self.last_pd_us > WATCHDOG_US

    def sync_error(self) -> bool:
        return sync_error_reached(self.sync_counter, SYNC_ERROR_COUNTER_LIMIT)

    def _supervise(self) -> None:
        """OP -> SAFEOP on the Sync Manager watchdog or a sync error (Tab. 12)."""
        if self.esm.state is not AlState.OP:
            return
        if self.pd_watchdog_expired():
            self.esm.fall(AlState.SAFEOP, ErrorKind.WATCHDOG, SM_WATCHDOG, self.now_us)
            self.emit(LogLine(self.now_us, self.device_id, text="Sync Manager watchdog: no "
                              "process data for 100 ms, OP -> SAFEOP"))
        elif self.sync_error():
            self.esm.fall(AlState.SAFEOP, ErrorKind.SYNC, SYNC_ERROR, self.now_us)
            self.emit(LogLine(self.now_us, self.device_id, text="sync error counter "
                              "reached 0x10F1:2, OP -> SAFEOP"))

    def _process_data(self) -> None:
        state = self.esm.state
        supply_ok = self.u_out_ok
        memo = self._memo if self.SKIP_STILL else None
        for module in self.modules:
            values = self._output_values(module)
            if memo is None:
                module.drive_outputs(values, supply_ok)
            else:
                memo.drive(module, values, supply_ok)
            if state in (AlState.SAFEOP, AlState.OP):  # Tab. 11: inputs from SAFEOP on
                if memo is None:
                    module.sample_inputs()
                else:
                    memo.sample(module)
        if state in (AlState.SAFEOP, AlState.OP):
            self._bus_inputs()

    def _output_values(self, module: CpxModule) -> list[int]:
        """OP: what the PLC wrote. Otherwise 0x2400:7 decides (Tab. 11: in SAFEOP the
        outputs do not keep their state): 0 all off, 1 hold the last state, 2 failsafe."""
        if self.esm.state is AlState.OP:
            module.held = list(module.out_values)
            return module.out_values
        mode = int(self.od.peek(0x2400, 7)) if self.od is not None else 0
        if mode == 1:
            return module.held
        if mode == 2:
            return module.failsafe
        return [0] * len(module.out_values)

    def _bus_inputs(self) -> None:
        mode = self.switches.active_mode
        if mode is DiagMode.STATUS_BITS:
            bits = self.diagnosis.status_bits
            self.bus.in_values = [bits >> i & 1 for i in range(8)]
        elif mode is DiagMode.IO_DIAGNOSIS:
            # The request is an output word: taken in OP only (Tab. 11: SAFEOP updates the
            # inputs only); the answer, an input, follows the request taken last.
            if self.esm.state is AlState.OP:
                self.sti_request = self.bus.out_values[0]
            self.bus.in_values = [self.diagnosis.interface_word(self.sti_request)]

    def _at_terminals(self, set_v: float, fault: str) -> float:
        """What a meter on the supply reads (U_EL/SEN at [XD], Tab. 8; U_OUT at its feed):
        the set value, or the sag while its undervoltage is injected (the fault only pulls
        the supply down)."""
        return min(set_v, INJECTED_SAG_V) if self.has_fault(fault) else set_v

    @property
    def u_out_v(self) -> float:
        return self._at_terminals(self.out_v, "undervoltage_out")

    @property
    def u_el_sen_v(self) -> float:
        return self._at_terminals(self.el_sen_v, "undervoltage_el_sen")

    @property
    def u_out_ok(self) -> bool:
        return self.u_out_v >= SUPPLY_MIN_V

    @property
    def u_el_sen_ok(self) -> bool:
        return self.u_el_sen_v >= SUPPLY_MIN_V

    def monitors(self) -> Monitors | None:
        """0x2400's monitoring switches (Tab. 27); None without a dictionary (unpowered)."""
        od = self.od
        if od is None:
            return None
        return Monitors(scs=bool(od.peek(0x2400, 2)), sco=bool(od.peek(0x2400, 3)),
                        v_out=bool(od.peek(0x2400, 4)))

    def _diagnose(self) -> None:
        monitors = self.monitors()
        assert monitors is not None
        faults: list[tuple[ModuleFault, ModuleType]] = []
        if not self.u_el_sen_ok:
            faults.append((ModuleFault(0, "undervoltage_el_sen"), self.bus.mtype))
        supply_ok, memo = self.u_out_ok, self._memo
        for module in self.modules:
            found = memo.faults(module, monitors, supply_ok) if self.SKIP_STILL else \
                module.faults(monitors, supply_ok)
            faults.extend((f, module.mtype) for f in found)
        self.diagnosis.update(faults, self.now_us, self._t_ns())

    def _t_ns(self) -> int:
        """Tab. 16 time stamp: time since the bus module started, in ns."""
        return (self.now_us - self.power_on_us) * 1000

    def _filter_no_error(self) -> bool:
        return self.od is not None and bool(self.od.peek(0x2401, 0))

    def _reports_errors(self) -> bool:
        """CPX error messages reach the PLC only with the I/O diagnostic interface active
        since the last start (§2.5 note; docs/cpx-e-ec.md choice 33)."""
        return self.switches.active_mode is DiagMode.IO_DIAGNOSIS

    def has_fault(self, name: str) -> bool:
        return name in self.fault_names

    def faults_changed(self) -> None:
        self.fault_names = frozenset(f.name for f in self.injected)

    # ---- LEDs -----------------------------------------------------------------------------
    def _refresh_leds(self) -> None:
        self.leds.update(self.now_us, wanted_leds(self), self.emit)

    def clock_key_now(self) -> tuple[Any, ...]:
        """:func:`~devices.cpx.stillness.clock_key`, the methods it asks inline (the still
        step's test, every step; tests/devices/cpx/test_cpx_step_cost.py compares the two)."""
        esm, now, last, low = self.esm, self.now_us, self.last_frame_us, self.low_since_us
        return (esm.state, esm.error, esm.code, esm.requested,
                now - self.last_pd_us > WATCHDOG_US,
                self.sync_counter >= SYNC_ERROR_COUNTER_LIMIT,  # sync_error_reached
                last is not None and now - last <= ACTIVITY_WINDOW_US,
                now - (last if last is not None else self.power_on_us) > WATCHDOG_US,
                low is not None and now - low >= BRIDGING_US)

    # ---- quiet spans (docs/cpx-e-ec.md "Quiet spans") --------------------------------------
    def quiet_until(self, step_us: int) -> int:
        """The last step up to which every step would be a still step (stillness.py): nothing
        touched the model since a full step of this length changed nothing, and each clock
        comparison of :meth:`clock_key_now` keeps, at every step of the span, the value the
        still step was proved with. Without frames each comparison flips at most once, at a
        time known now (the last frame / process data / power-up / supply dip plus its
        window): the span ends before the first flip still ahead. With the master's frames
        (:meth:`frames_quiet` true) the comparisons hold the same values (see there)."""
        now = self.now_us
        still = self._still
        if self._touched or still.dt != step_us or not self.SKIP_STILL:
            return now  # the next step runs in full (the cheap "no", asked often in motion)
        esm, last, pd, low = self.esm, self.last_frame_us, self.last_pd_us, self.low_since_us
        first = now + step_us
        base = last if last is not None else self.power_on_us
        pd_over = first - pd > WATCHDOG_US
        traffic = last is not None and first - last <= ACTIVITY_WINDOW_US
        silent = first - base > WATCHDOG_US
        bridged = low is not None and first - low >= BRIDGING_US
        if still.clock != (esm.state, esm.error, esm.code, esm.requested, pd_over,
                           self.sync_counter >= SYNC_ERROR_COUNTER_LIMIT, traffic, silent,
                           bridged):
            return now  # the next step is not the still one
        # The last time each comparison still has its value at ``first`` (none: no end).
        end = now + QUIET_HORIZON_STEPS * step_us
        if not pd_over:
            end = pd + WATCHDOG_US
        if traffic:  # base is last: traffic's window ends before "no master" (50 < 100 ms)
            if base + ACTIVITY_WINDOW_US < end:
                end = base + ACTIVITY_WINDOW_US
        elif not silent and base + WATCHDOG_US < end:
            end = base + WATCHDOG_US
        if low is not None and not bridged and low + BRIDGING_US - 1 < end:
            end = low + BRIDGING_US - 1
        return now + (end - now) // step_us * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        """As the still steps up to ``t_us`` (:meth:`quiet_until`): the clock moves, the
        still-step count grows; nothing else does."""
        now, still = self.now_us, self._still
        if t_us == now:
            return
        if t_us < now or self._touched or not still.dt:
            raise ValueError(f"{self.device_id}: no quiet steps to {t_us} us (now {now} us)")
        still.skipped += (t_us - now) // still.dt
        self.now_us = t_us

    def traffic(self) -> bool:
        return self.last_frame_us is not None and \
            self.now_us - self.last_frame_us <= ACTIVITY_WINDOW_US

    def master_silent(self) -> bool:
        """No frame for a watchdog time: "no connection to the master / master inactive"."""
        last = self.last_frame_us if self.last_frame_us is not None else self.power_on_us
        return self.now_us - last > WATCHDOG_US

    # ---- object dictionary callbacks ------------------------------------------------------
    def od_error_register(self) -> int:
        return self.diagnosis.error_register

    def od_status_register(self) -> int:
        return self.diagnosis.status_bits

    def od_history_message(self, sub: int) -> bytes:
        # an empty slot lies above sub 0: a master's read aborts before it (history.read),
        # only the dashboard's peek sees it, as no bytes
        message = self.history.message(sub)
        return b"" if message is None else message.encode()

    def od_f030_written(self, _value: Any) -> None:
        self.f030_written = True

    def od_unique_id(self) -> str:
        return f"{self.serial:08X}"

    # ---- views ----------------------------------------------------------------------------
    def _module_view(self, module: CpxModule, monitors: Monitors | None,
                     runs: bool) -> dict[str, Any]:
        pairs = [(e.fault.cause, e.fault.channel) for e in self.diagnosis.active
                 if e.fault.module == module.number]
        diagnosed = self.diagnosis.of_module(module.number)
        return {**module.snapshot(), "diagnosed": diagnosed,
                "held_off": held_off(module.held_off(), diagnosed),
                "error_led": self.diagnosis.error_led(module.number),
                "undiagnosed": undiagnosed(module, pairs, monitors, runs, self.u_out_ok)}

    def snapshot(self) -> dict[str, Any]:
        mtypes = [m.mtype for m in self.modules]
        monitors, runs = self.monitors(), self.application_runs
        return {
            "kind": self.KIND, "id": self.device_id, "powered": self.powered,
            "esm": self.esm.state.label, "requested": self.esm.requested.label,
            "al_status": self.esm.register, "al_status_code": self.esm.code,
            "box_name": self.box_name, "station_address": self.station_address,
            "explicit_device_id": self.explicit_device_id, "id_loaded": self.id_loaded,
            "leds": self.leds.channel_patterns(), "led_states": self.leds.snapshot(),
            "switches": self.switches.snapshot(),
            "supply": {"el_sen_v": self.u_el_sen_v, "out_v": self.u_out_v,
                       "el_sen_ok": self.u_el_sen_ok, "out_ok": self.u_out_ok},
            "ports": {"in": self.link_in, "out": self.link_out, "traffic": self.traffic()},
            "application": self.application_runs, "boot_failed": self.boot_failed,
            "bus_module": self.bus.snapshot(),
            # each module with what the bus module diagnoses on it and the red LED that
            # shows, not only its wiring: a short on an output switched off is no fault yet
            # (choice 30); and, the instructor's, what is wired but not diagnosed and why
            "modules": [self._module_view(m, monitors, runs) for m in self.modules],
            "addresses": [a.row() for a in assign_addresses(self.bus.mtype, mtypes)],
            "address_space": self.space.snapshot() if self.space else None,
            "space_error": self.space_error,
            "diagnosis": self.diagnosis.snapshot(), "history": self.history.snapshot(),
            "f030_written": self.f030_written, "sync_counter": self.sync_counter,
            # the named faults it has, module conditions included (a failed module is a fault)
            "injected": [f.entry() for f in held(self.injected, self.modules)],
        }
