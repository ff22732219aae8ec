"""The FastCAT EtherCAT coupler (seed 000): power, internal-bus scan, CNF, ESM, alarms, LEDs.

One internal-bus exchange per ``step``. The rail holds the modules in slot order (``None`` for
an empty slot); the last scan numbers the modules that answered 1..n along the bus, and that
numbering is what the object dictionary, the emergency byte 0 and the 0x80XX codes use.
Every alarm is a *cause* (injected by an operator or physical: a module that does not answer,
the Ethernet cable, the Tbus supply, a module's own alarm); only the first cause is latched
(§7), and a Reset fault or a resync clears it only when its cause is gone.
Behaviour and choices: docs/fastcat-coupler.md. A step that would repeat a step in which nothing
changed is skipped; state changes from outside come through ``apply``, ``request_state`` and the
object dictionary, which mark the model touched (docs/performance.md).
"""

from __future__ import annotations

import json
import logging
import random
from collections.abc import Mapping
from typing import Any, ClassVar

from devices.device import Action, DeviceModel
from devices.esm import AlStatusView, CoeMailbox
from devices.ethercat import AlState
from devices.events import StateChanged
from devices.fastcat.alarms import COUPLER, REFUSAL_AL_STATUS, Alarm
from devices.fastcat.bus import BusMixin
from devices.fastcat.catalog import module_type
from devices.fastcat.causes import cause_facts, config_view, expected_in_slot
from devices.fastcat.cnf import BusScan, CnfButton, ScanPhase
from devices.fastcat.esm import SM_WATCHDOG, SM_WATCHDOG_US, ErrorKind, Esm, request_refusal
from devices.fastcat.faults import FaultsMixin
from devices.fastcat.leds_fastcat import (
    err_led,
    module_led_patterns,
    module_light,
    run_led,
)
from devices.fastcat.modules import IoModule
from devices.fastcat.objects import MAX_MODULES, build_od
from devices.fastcat.rail import COUPLER_ACTIONS, MODULE_ACTIONS, RailMixin
from devices.flash import FlashError, FlashStore, MemoryFlash
from devices.leds import LedBank, link_led
from devices.od import AbortCode, ObjectDictionary, SdoAbort

logger = logging.getLogger(__name__)

CNF_BUTTON = "cnf_button"  # StateChanged.machine of the button: released / pressed
CNF_PROCEDURE = "cnf"  # StateChanged.machine of the procedure: idle, resetting, scanning, ...
ACTIVITY_WINDOW_US = 50_000  # LINK flickers while the master sent a frame this recently
QUIET_FOREVER_STEPS = 1 << 40  # a quiet span with no end of its own (the rig caps it)
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_INIT, _OP, _NO_CNF = AlState.INIT, AlState.OP, ScanPhase.IDLE
# A span with LINK activity ends at its lapse, before the SM watchdog can expire (quiet_until).
assert ACTIVITY_WINDOW_US < SM_WATCHDOG_US


class FastCat(BusMixin, FaultsMixin, RailMixin, CoeMailbox, AlStatusView, DeviceModel):
    KIND = "fastcat"
    QUIET_SNAPSHOT = True  # tests/hardening/test_revision.py
    SKIP_SAME_WRITES = True  # objects.py: a write of the value an output holds is no touch
    ACTIONS: ClassVar[Mapping[str, Action]] = {**MODULE_ACTIONS, **COUPLER_ACTIONS}

    def __init__(self, device_id: str, rng: random.Random,
                 modules: list[tuple[str, Mapping[str, Any]]], rotary_switch: int = 1,
                 flash: FlashStore | None = None, master_address: int = 1,
                 box_name: str = "Box 1 (FastCAT)", station_address: int = 1001) -> None:
        super().__init__(device_id=device_id, rng=rng)
        if len(modules) > MAX_MODULES:
            raise ValueError(f"{len(modules)} modules: a FastCAT takes at most {MAX_MODULES} "
                             f"(seed 000 §2)")
        if not 1 <= rotary_switch <= 15:
            raise ValueError(f"rotary switch {rotary_switch}: the FastCAT switch reads 1..15 "
                             f"(seed 000 §6.19)")
        self.rail: list[IoModule | None] = [
            self._new_module(name, options, slot) for slot, (name, options)
            in enumerate(modules, start=1)]
        self.shelf: dict[int, IoModule] = {}  # last module unplugged from each slot
        self.flash = flash if flash is not None else MemoryFlash()
        self.stored = self._load_stored()
        self.rotary_switch = rotary_switch
        self.master_address = master_address  # the built-in master's, for §6.19's check
        # §6.19 with a master on the wire: the configured station address (ESC 0x0010) it
        # wrote; None while the built-in master drives the line (faults.py logical_address)
        self.wire_station: int | None = None
        self.box_name = box_name
        self.station_address = station_address
        self.serial = self.rng.getrandbits(32)
        self.link = True
        # The IN link: the line's cable (line_in, the master's set_link) and the operator's
        # own plug (plugs: IN, OUT; the master folds them into its line model).
        self.line_in, self.plugs = True, (True, True)
        self.tbus_low = False
        self.injected: list[Alarm] = []
        # Speed (docs/performance.md). A step is skipped when it would repeat one that changed
        # nothing: _settled = (step length, LINK activity) of that step; _touched = something
        # may have changed since (a command, an AL control write, an object write);
        # _modules_touched = a module's inputs may have (a command, a module object write).
        self._touched, self._modules_touched, self._settled = True, True, None
        self._woken: list[IoModule] = []  # a field command's modules (rail.py FIELD_ACTIONS)
        self._bus_still = False
        # Derived tables with what they were computed from (bus.py, faults.py, LEDs).
        self._bus_key, self._bus, self._rebound_for, self._answering = (), [], None, None
        self._exchange_key: tuple[int, bool] | None = None
        self._answer_cache: tuple[Any, ...] | None = None
        self._moving: tuple[Any, list[tuple[int, IoModule]]] = (None, [])
        self._stepped: list[tuple[int, IoModule]] | None = None
        self._quiet = False  # faults.py: the last alarm search in a step found no cause
        self._scan_causes_key: tuple[Any, ...] | None = None
        self._led_key: tuple[Any, ...] = ()
        self.esm = Esm(self.emit, device_id, stop_mailbox=self._stop_mailbox,
                       leave_op=self._leave_op)
        self.cnf = CnfButton()
        self.leds = LedBank(device_id)
        self.cnf_phase = ScanPhase.IDLE
        self.powered = False
        self._power_up_state()
        self.cmd_power(True)

    # ---- construction and power -----------------------------------------------------------
    def _new_module(self, name: str, options: Mapping[str, Any] | None, slot: int) -> IoModule:
        try:
            mtype = module_type(name)
        except KeyError as exc:
            raise ValueError(f"slot {slot}: {exc.args[0]}") from None
        try:
            return IoModule(mtype, random.Random(self.rng.getrandbits(64)), dict(options or {}))
        except ValueError as exc:
            raise ValueError(f"slot {slot} ({name}): {exc}") from None

    def _load_stored(self) -> list[str] | None:
        raw = self.flash.load()
        if raw is None:
            return None
        try:
            names = json.loads(raw.decode("utf-8"))
            if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
                raise ValueError("not a list of module names")
            for name in names:
                module_type(name)
        except (ValueError, KeyError, UnicodeDecodeError) as exc:
            logger.warning("%s: unreadable stored configuration ignored: %s",
                           self.device_id, exc)
            return None
        return names

    def _power_up_state(self) -> None:
        self.rotary_read = self.rotary_switch  # §6.20: read like a switch, at power-up
        self.address_check = 0
        self.reset_bit = 0
        self.alarm: Alarm | None = None
        self.edge_causes: list[Alarm] = []  # one-shot causes (a failed flash write)
        self.raised: list[Alarm] = []  # alarms the modules raised, cause still present
        self.fresh_raised: list[Alarm] = []  # raised during this exchange
        self.address_fault = False
        self.mailbox: list[bytes] = []
        # The master's process-data outputs written before OP, (index, sub) -> value, in the
        # order written: the SM2 buffer the coupler takes at its first OP cycle.
        self.sm2_waiting: dict[tuple[int, int], int] = {}
        self.last_frame_us: int | None = None
        self.scan: BusScan | None = None
        self.scan_found: list[IoModule] = []
        self.booted = False
        self.detected: list[tuple[int, str]] = []  # (rail slot, type) per module number
        self.detected_us: int | None = None  # when the scan that found ``detected`` read the Tbus
        self.bound: list[IoModule] = []  # the module instance each module number talks to
        self.comm_errors: list[int] = []
        self.od: ObjectDictionary | None = None
        self._forget_configured()

    def cmd_power(self, on: bool) -> None:
        if on == self.powered:
            return
        self.powered = on
        if on:
            self._power_up_state()
            for module in self.modules():
                module.reset()
            self._start_scan(cnf=False)
        else:
            self.scan = None
            if self.cnf.release(self.now_us) is not None:  # a dead coupler reads no button
                self.emit(StateChanged(self.now_us, self.device_id, from_state="pressed",
                                       to_state="released", machine=CNF_BUTTON))
            self.esm.drop_to_init(self.now_us)
            self._clear_alarm()
            self.od = None
            self.detected, self.bound = [], []
            self.detected_us = None
        self._refresh()

    def modules(self) -> list[IoModule]:
        return [m for m in self.rail if m is not None]

    # ---- the master's side ----------------------------------------------------------------
    def reachable(self) -> bool:
        return self.powered and self.link

    def exchange_frame(self, now_us: int) -> None:
        """The master's frame passed through this slave (drives the LINK LED)."""
        # reachable(), inline: the master calls this every cycle, and CPython 3.11 leaves the
        # method lookups on this model unspecialised (docs/performance.md "Session 23")
        if self.powered and self.link:
            self.last_frame_us = now_us

    def take_emergencies(self) -> list[bytes]:
        """Emergency data queued in the mailbox; it runs from PREOP on (ETG.1000.6)."""
        if not self.mailbox or not self.reachable() or self.esm.state is _INIT:
            return []
        out, self.mailbox = self.mailbox, []
        return out

    def _stop_mailbox(self) -> None:
        """Any state -> INIT (devices/esm.py; a master's request, the CNF procedure, power
        loss): the emergencies not read yet are lost. 0x5400 follows the latched alarm."""
        self.mailbox = []

    def _leave_op(self) -> None:
        """OP left (devices/esm.py ``Esm.leave_op``: a request refused in OP): as after a
        requested OP -> SAFEOP, the outputs follow the ESM at the next exchange (bus.py: enabled
        in OP only), so that step runs in full."""
        self._touched = True

    def take_station_address(self, address: int | None) -> None:
        """The master that drives the line gave the coupler its address: a wire master's
        configured station address (ESC 0x0010), or None for the built-in master, whose own
        setting is ``master_address`` (seed 000 §6.19, docs/fastcat-coupler.md "Address
        check"). Kept over a power cycle: the register is the ESC's, which the wire keeps and
        a master writes again, unchanged, when it brings the slave back."""
        if address != self.wire_station:
            self.wire_station = address
            self._touched = True  # the cause of a latched 0x12 may be gone (faults.py)

    def request_state(self, target: AlState, ack: bool = False) -> None:
        """AL control write. The answer is in ``al_status`` / ``al_status_code``."""
        self._touched = True
        if not self.reachable():
            return
        now, esm = self.now_us, self.esm
        if not esm.take_request(target, ack, now):  # bit 4 "Error Ind Ack" (ETG.1000.6)
            return
        esm.requested = target
        refusal = request_refusal(esm.state, target)
        if target is esm.state:
            esm.accept(target, now)
        elif refusal is not None:
            esm.refuse(refusal, now)
        elif target is AlState.INIT:
            esm.accept(target, now)
            self._start_scan(cnf=False)  # §3: a scan on every return to INIT
        elif esm.state is AlState.INIT:
            if self.scan is None:  # else INIT -> PREOP completes when the scan ends
                esm.accept(target, now)
        elif target in (AlState.SAFEOP, AlState.OP) and self.alarm is not None \
                and (code := self.alarm.refusal_code) is not None:
            esm.refuse(code, now)  # a coupler alarm; a module alarm bars nothing
        elif esm.state is AlState.SAFEOP and target is AlState.OP \
                and not self._process_data_fresh(now):
            esm.refuse(SM_WATCHDOG, now, ErrorKind.WATCHDOG)  # SSC: outputs first (bWdTrigger)
        elif esm.state is AlState.PREOP and target is AlState.SAFEOP \
                and self._slot_mismatch() is not None:
            self.slot_fault = True  # §7.5 0x14: checked on the transition to SAFEOP
            self._evaluate_alarms()
            esm.refuse(REFUSAL_AL_STATUS[COUPLER, 0x14], now)  # §7.7 0x0070
        elif target is AlState.OP and self.address_check and self._address_mismatch():
            self.address_fault = True  # §6.19: checked on the transition to OP
            self._evaluate_alarms()  # 0x12 latched: the ESM fell to PREOP (§7.7 0x8012)
            if esm.state is AlState.SAFEOP:  # 0x12 waits behind a module alarm: no refusal
                esm.accept(target, now)
        else:
            esm.accept(target, now)
        esm.settle_request(now)
        if esm.state is AlState.OP and self.sm2_waiting:
            self._take_waiting_outputs()
        self._refresh()

    def _process_data_fresh(self, now_us: int) -> bool:
        """A master's frame (its SM2 write) came within the SM watchdog time."""
        last = self.last_frame_us
        return last is not None and now_us - last <= SM_WATCHDOG_US

    def write_process_output(self, index: int, sub: int, value: int) -> None:
        """An RxPDO entry of the master's process image (SM2; the wire face's outputs). The
        coupler acts on its outputs in OP only: in PREOP / SAFEOP they stay in their safe
        state (ETG.1000.6; seed 000 §7: Reset fault is "mappato nei dati scambiati con il
        coupler"), so a value written before OP waits in the SM buffer for the first OP
        cycle, where a Reset fault rising edge counts (docs/fastcat-coupler.md "Process data
        before OP"). An SDO or the dashboard writes the object itself (``write_object``)."""
        if self.esm.state is AlState.OP:
            self._require_od().write(index, sub, value)
            return
        self.sm2_waiting.pop((index, sub), None)  # the order of the master's last writes
        self.sm2_waiting[(index, sub)] = value

    def _take_waiting_outputs(self) -> None:
        """The first OP cycle reads the SM2 buffer the master wrote before OP."""
        waiting, self.sm2_waiting = self.sm2_waiting, {}
        od = self.od
        if od is None:
            return
        for (index, sub), value in waiting.items():
            if (index, sub) not in od:
                continue  # the scan since changed the mapping: no such output now
            try:
                od.write(index, sub, value)
            except SdoAbort as exc:
                logger.info("%s: output 0x%04X:%d not applied: %s", self.device_id, index,
                            sub, exc)

    def frames_quiet(self) -> bool:
        """Quiet spans (links.py): a frame now, and any number of them while the coupler's
        own steps stay quiet, changes nothing but ``last_frame_us`` (:meth:`skip_frames`).
        Unreachable, a frame does nothing. Reachable, a frame keeps LINK activity on for the
        next :data:`ACTIVITY_WINDOW_US`: that changes no step only if the settled step saw
        activity (``_settled[1]``); the master's mailbox read must also find nothing."""
        if not (self.powered and self.link):
            return True
        if self.mailbox and self.esm.state is not AlState.INIT:
            return False  # take_emergencies would empty the mailbox
        settled = self._settled
        return settled is not None and settled[1] and not self._touched

    def skip_frames(self, n: int, last_us: int) -> None:
        """As ``n`` frames, one per master cycle, the last at ``last_us``."""
        if n > 0 and self.powered and self.link:
            self.last_frame_us = last_us

    # ---- stepping ---------------------------------------------------------------------------
    def quiet_until(self, step_us: int) -> int:
        """The quiet span (devices/device.py): every step up to T takes the still branch of
        :meth:`step`. Unpowered, a step only moves the clock: no end. Powered, the settled
        step's (step length, LINK activity) must repeat; with no command, the only input of
        that test that moves with time is the activity (no frame for more than
        :data:`ACTIVITY_WINDOW_US`), which without frames turns off once, at
        ``last_frame_us + ACTIVITY_WINDOW_US``, and with frames stays on (frames_quiet)."""
        now = self.now_us
        if not self.powered:
            return now + QUIET_FOREVER_STEPS * step_us
        settled = self._settled
        if self._touched or settled is None or settled[0] != step_us:
            return now
        last = self.last_frame_us
        if settled[1]:  # activity must stay on: it does up to last + window without frames
            if last is None:
                return now
            return now + max(0, (last + ACTIVITY_WINDOW_US - now) // step_us) * step_us
        if last is not None and now + step_us - last <= ACTIVITY_WINDOW_US:
            return now  # a frame since the settled step: the next step sees activity
        if self.esm.state is _OP:  # the SM watchdog expires at the first step after last + WD
            if last is None:
                return now
            return now + max(0, (last + SM_WATCHDOG_US - now) // step_us) * step_us
        return now + QUIET_FOREVER_STEPS * step_us  # off, and stays off without frames

    def skip_to(self, t_us: int, step_us: int) -> None:
        """The still steps up to ``t_us`` move only the clock (:meth:`step`)."""
        if t_us < self.now_us:
            raise ValueError(f"{self.device_id}: time went backwards ({t_us} < {self.now_us})")
        self.now_us = t_us

    def step(self, now_us: int) -> None:
        dt_us = now_us - self.now_us
        if dt_us < 0:  # DeviceModel.step, inline (every step: super() costs a lookup)
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {self.now_us})")
        self.now_us = now_us
        if not self.powered:
            return
        # LINK activity: only the master's frame (exchange_frame, outside this step) moves
        # last_frame_us, so it is the same at the start and the end of the step
        activity = self._activity(now_us)
        if not self._touched and self._settled == (dt_us, activity) \
                and (activity or not self._watchdog_due(now_us)):
            return  # the same inputs as a step that changed nothing: nothing changes
        touched = self._modules_touched
        if self._touched:
            self._answer_cache = None  # a command may have changed who answers (bus.py)
            self._quiet = False  # ... or brought an alarm cause (faults.py)
        self._touched, self._modules_touched, self._bus_still = False, False, False
        queued = len(self.events.items)
        if self.cnf.release_due(now_us):
            self._on_cnf_release()
        # before the exchange: this cycle's outputs are safe. LINK activity (a frame within
        # ACTIVITY_WINDOW_US <= SM_WATCHDOG_US) rules the watchdog out without asking it.
        if not activity and self._watchdog_due(now_us):
            self.esm.fall_to(AlState.SAFEOP, ErrorKind.WATCHDOG, SM_WATCHDOG, now_us)
        if self.scan is not None:
            self._exchange_key = None  # no cycle: the next one starts afresh
            self._answer_cache = None  # the scan may bind other modules (bus.py)
            self._quiet = False  # and find other causes (faults.py)
            self._advance_scan(self.scan)
        elif self.booted:
            self._exchange(dt_us, touched)
        self._evaluate_alarms()
        self._refresh(activity)
        self._answering = None  # valid only inside this step
        settled = (self._bus_still and self.scan is None and not self.cnf.pressed
                   and not self.raised and not self.fresh_raised
                   and len(self.events.items) == queued)
        self._settled = (dt_us, activity) if settled else None

    def _touch(self, module: bool) -> None:
        """An object write: by the master, an SDO client or a command."""
        self._touched = True
        if module:
            self._modules_touched = True

    def _build_od(self) -> None:
        """The object dictionary of the modules now bound; writes into it touch the model."""
        self.od = build_od(self, self.bound, self.serial, self._touch)

    def _watchdog_due(self, now_us: int) -> bool:
        """The SM watchdog expired in OP: no process data for more than SM_WATCHDOG_US (ESC
        0x0420). Activity (a frame within ACTIVITY_WINDOW_US) rules it out."""
        return self.esm.state is _OP and not self._process_data_fresh(now_us)

    def _activity(self, now_us: int) -> bool:
        """LINK traffic: the master sent a frame within the activity window."""
        return self.last_frame_us is not None and now_us - self.last_frame_us <= ACTIVITY_WINDOW_US

    # ---- scan and CNF ---------------------------------------------------------------------
    def _start_scan(self, cnf: bool) -> None:
        self.scan_found = [m for m in self.rail if m is not None and m.responds()]
        slots = tuple(self.rail.index(m) + 1 for m in self.scan_found)
        self.scan = BusScan(self.now_us, slots, cnf=cnf)

    def _advance_scan(self, scan: BusScan) -> None:
        if not scan.detected_applied and scan.scanned(self.now_us):
            scan.detected_applied = True
            self.detected_us = self.now_us
            self.detected = [(slot, m.mtype.name) for slot, m in zip(scan.slots,
                                                                     self.scan_found,
                                                                     strict=True)]
            self.bound = list(self.scan_found)
            self.raised = []  # module numbers change with the new scan
            self.comm_errors = [0] * len(self.bound)
            self._forget_configured()  # the master writes it again at its next start-up
            self._build_od()
        if scan.finished(self.now_us):
            if scan.cnf:
                self._store_configuration()
            self.scan = None
            self.booted = True
            self._try_reset(resync=True)  # the master took the line through INIT
            self._evaluate_alarms()
            if self.esm.state is AlState.INIT and self.esm.requested is AlState.PREOP:
                self.esm.accept(AlState.PREOP, self.now_us)

    def _store_configuration(self) -> None:
        names = [name for _slot, name in self.detected]
        try:
            self.flash.save(json.dumps(names).encode("utf-8"))
        except FlashError as exc:
            logger.info("%s: configuration not stored: %s", self.device_id, exc)
            self.edge_causes.append(Alarm(COUPLER, 0x11))  # §7.5 SAVE_FLASH
            return
        self.stored = names

    def cmd_press_cnf(self) -> None:
        self._press_cnf(None)

    def cmd_release_cnf(self) -> None:
        self._on_cnf_release()

    def cmd_hold_cnf(self, seconds: float) -> None:
        self._press_cnf(round(seconds * 1_000_000))

    def _press_cnf(self, hold_us: int | None) -> None:
        if not self.powered:
            return  # a dead coupler does not read its button
        was_pressed = self.cnf.pressed
        self.cnf.press(self.now_us, hold_us=hold_us)
        if not was_pressed:
            self.emit(StateChanged(self.now_us, self.device_id, from_state="released",
                                   to_state="pressed", machine=CNF_BUTTON))

    def _on_cnf_release(self) -> None:
        held = self.cnf.release(self.now_us)
        if held is None:
            return
        self.emit(StateChanged(self.now_us, self.device_id, from_state="pressed",
                               to_state="released", machine=CNF_BUTTON))
        if not self.powered or not CnfButton.long_enough(held):
            return  # §2: a press shorter than three seconds does nothing
        if self.scan is not None and self.scan.cnf:
            return
        self.esm.drop_to_init(self.now_us)
        for module in self.modules():
            module.reset()  # §2: "il coupler resetta tutti i moduli presenti sul bus interno"
        self._start_scan(cnf=True)
        self._refresh()

    # ---- object dictionary --------------------------------------------------------------
    def od_comm_errors(self, n: int) -> int:
        return self.comm_errors[n - 1] if n <= len(self.comm_errors) else 0

    def od_address_check(self) -> int:
        return self.address_check

    def od_set_address_check(self, value: int) -> None:
        self.address_check = int(value)

    def od_rotary(self) -> int:
        return self.rotary_read

    def od_module_answers(self, n: int) -> bool:
        return self._answers(n)

    def od_configured(self, sub: int) -> int:
        return self.configured[sub]

    def od_set_configured(self, sub: int, value: int) -> None:
        if self.esm.state is not AlState.PREOP:  # ETG.5001: the master's PRE-OP start-up
            raise SdoAbort(AbortCode.CANNOT_STORE_STATE, 0xF030, sub)
        self.configured[sub] = int(value)

    def _forget_configured(self) -> None:
        """0xF030 back to "not configured": volatile, rebuilt with the dictionary."""
        self.configured = [0] * (MAX_MODULES + 1)
        self.slot_fault = False

    # ---- what the outside sees --------------------------------------------------------------
    def _refresh(self, activity: bool | None = None) -> None:
        """After any change: modules' alarm flag (§7), CNF phase, LED patterns. ``activity``:
        the LINK activity now, when the caller (a step) has it already."""
        in_alarm = self.powered and self.alarm is not None
        for module in self.rail:
            if module is not None:
                module.in_alarm = in_alarm
        scan = self.scan
        phase = scan.phase(self.now_us) if scan is not None and scan.cnf else _NO_CNF
        if phase is not self.cnf_phase:
            self.emit(StateChanged(self.now_us, self.device_id, from_state=self.cnf_phase.value,
                                   to_state=phase.value, machine=CNF_PROCEDURE))
            self.cnf_phase = phase
        self._refresh_leds(activity)

    def _refresh_leds(self, activity: bool | None = None) -> None:
        now, rail, powered, scan = self.now_us, self.rail, self.powered, self.scan
        if activity is None:
            activity = self._activity(now)
        if self._answering is not None and rail == self._bus:
            alive = self._answering  # in a step, with every module on the bus: the same list
        else:
            alive = [m is not None and powered and m.responds() for m in rail]
        head = (powered, self.esm.state, self.alarm, self.esm.error, self.link, activity,
                None if scan is None else (scan, scan.phase(now), scan.recognised(now)))
        last = self._led_key
        if last and last[0] == head and last[1] == rail and last[2] == self.bound \
                and last[3] == alive:
            return  # the patterns depend on nothing else: no change
        self._led_key = (head, list(rail), list(self.bound), alive)
        wanted = {"RUN": run_led(powered, self.esm.state),
                  "ERR": err_led(powered, self.alarm, self.esm.error),
                  "LINK": link_led(powered, self.link, activity)}
        for slot, module in enumerate(rail, start=1):
            if module is not None:
                light = module_light(alive[slot - 1], slot, scan, now,
                                     addressed=module in self.bound,
                                     in_alarm=self.alarm is not None)
                wanted.update(module_led_patterns(slot, light))
        self.leds.update(now, wanted, self.emit)

    # ---- views ------------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        alarm = self.alarm
        scan = self.scan
        causes = cause_facts(self)
        present = {(c["table"], c["code"], c["module"]) for c in causes}
        return {
            "kind": self.KIND, "id": self.device_id, "powered": self.powered,
            "esm": self.esm.state.label, "requested": self.esm.requested.label,
            "al_status": self.esm.register, "al_status_code": self.esm.code,
            "station_address": self.station_address, "rotary_switch": self.rotary_switch,
            "rotary_read": self.rotary_read, "address_check": bool(self.address_check),
            "fault_active": alarm is not None, "emergency_data": self.od_emergency_word(),
            "alarm": None if alarm is None else {
                "table": alarm.table, "code": alarm.code, "name": alarm.info.symbol,
                "description": alarm.info.description, "module": alarm.module,
                "resettable": alarm.resettable,
                "cause_present": (alarm.table, alarm.code, alarm.module) in present},
            "injected": [{"fault": a.info.symbol, "code": a.code, "module": a.module or None}
                         for a in self.injected],
            "link": self.link, "plugs": list(self.plugs), "tbus_low": self.tbus_low,
            # §6.17 0x5200:1, the level the master or the dashboard last wrote. Without supply
            # there is no object: it reads as its default (False) until it is written again.
            "reset_fault": self.powered and bool(self.reset_bit),
            "cnf": {"pressed": self.cnf.pressed,
                    "held_s": self.cnf.held_us(self.now_us) / 1_000_000,
                    "phase": self.cnf_phase.value},
            "scan": {"active": scan is not None,
                     "done": scan.recognised(self.now_us) if scan is not None
                     else len(self.detected),
                     "total": len(scan.slots) if scan is not None else len(self.detected)},
            "leds": self.leds.snapshot(),
            "rail": [self._slot_snapshot(slot, m) for slot, m in enumerate(self.rail, start=1)],
            "stored_config": None if self.stored is None else list(self.stored),
            "detected": [name for _slot, name in self.detected],
            # The facts behind the causes, the rail against flash and the last scan
            # (causes.py): the State tab's Causes and Configuration rows.
            "causes": causes, "config": config_view(self),
        }

    def _slot_snapshot(self, slot: int, module: IoModule | None) -> dict[str, Any]:
        if module is None:  # what belongs here: the dashboard's Plug offers it
            expected, source = expected_in_slot(self, slot)
            return {"slot": slot, "type": None, "expected": expected, "expected_from": source}
        numbers = [n for n, m in enumerate(self.bound, start=1)
                   if m is module and self.detected[n - 1][0] == slot]
        return {**module.snapshot(), "slot": slot, "type": module.mtype.name,
                "detected_as": self.detected[numbers[0] - 1][1] if numbers else None,
                "module_number": numbers[0] if numbers else None}
