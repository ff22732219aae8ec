"""The drive's CANopen node: NMT slave, SDO server, PDOs, SYNC, EMCY, heartbeat and guarding.

Seed 004 ch. 4 "Implementazioni nel Drive". A pure, clock-driven model: the runtime steps it
right after its drive (same instant), hands it received frames with :meth:`receive`, and takes
the frames it sent with :meth:`take_frames`, each stamped with the simulated instant it left
the bus. Every frame — received or sent — first waits for and occupies the node's
:class:`~devices.canopen.bus_timing.CanLine` at the bit rate of parameter n1.

The node follows its drive: it speaks only while the drive is powered and c9 was 5 (CANopen)
at the drive's power-up; c7 (node-ID) and n1 (bit rate) are those latched then. Its events
(NMT state, emergencies) are the drive's: they carry the drive's device id.
"""

from __future__ import annotations

import logging
import random
from collections import deque
from typing import Any, ClassVar

from devices.canopen import emcy as em
from devices.canopen.bus_timing import CanFrame, CanLine, bitrate_of_n1
from devices.canopen.comm_objects import (
    DEVICE_NAME,
    SYNC_COB_ID,
    build_comm_objects,
    build_profile_extras,
)
from devices.canopen.decode import Context
from devices.canopen.dictionary import CanOpenDictionary
from devices.canopen.eds import build_canopen_od
from devices.canopen.guarding import Heartbeat, NodeGuard
from devices.canopen.monitor import BusMonitor, pdo_text
from devices.canopen.nmt import (
    BOOT_UP_CODE,
    HEARTBEAT_BASE,
    NMT_COB_ID,
    NmtCommand,
    NmtState,
    Service,
    allows,
    next_state,
    parse_command,
)
from devices.canopen.pdo import ASYNC_TYPES, COB_INVALID, Pdo
from devices.canopen.process_data import ProcessData
from devices.canopen.sdo import SDO_RX_BASE, SdoChannel
from devices.device import Action, CommandError, DeviceModel, Param
from devices.events import EmergencySent, StateChanged
from devices.od import AbortCode, SdoAbort
from devices.servo.alarms import alarm_in_emergency, error_field_text
from devices.servo.drive import ServoDrive

logger = logging.getLogger(__name__)

BOOT_US = 50_000  # Initialisation after power-up: the drive's self test, then boot-up
RESET_COMMUNICATION_US = 5_000  # Initialisation after an NMT reset communication
FRAMES_IN_SNAPSHOT = 60
OUTBOX = 4096  # frames kept for an adapter that does not drain them (headless runs)
CALM_FOREVER = 1 << 62  # _calm_until when neither heartbeat nor life guarding is running
NO_STATE = "Off"  # the node is silent: drive off, or not on CANopen (c9 != 5)
SECOND_US = 1_000_000  # the bus-load mark moves at each new second
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_OPERATIONAL = NmtState.OPERATIONAL


class CanOpenNode(ProcessData, DeviceModel):
    KIND = "canopen"
    SKIP_QUIET = True  # False: every step in full (tests/hardening/test_still_steps.py)
    ACTIONS: ClassVar[dict] = {
        "frame": Action("frame", "A frame from a CANopen master on the bus (NMT, SYNC, SDO, "
                        "RPDO, ...): COB-ID and data bytes in hex, byte 0 first",
                        (Param("cob_id", int, low=0, high=0x7FF),
                         Param("data", str, required=False, default="",
                               doc="e.g. '2B 17 10 00 A0 0F 00 00'"),
                         Param("rtr", bool, required=False, default=False))),
    }

    def __init__(self, device_id: str, drive: ServoDrive, rng: random.Random | None = None,
                 device_name: str = DEVICE_NAME) -> None:
        super().__init__(device_id=device_id, rng=rng or random.Random(0))
        self.drive = drive
        self.device_name = device_name
        self.active = False
        self.state = NmtState.INITIALISATION
        self.node_id = drive.node_id
        self.bitrate = bitrate_of_n1(drive.latched_at_power_up["n1"])
        self.line = CanLine(self.bitrate)
        self.outbox: deque[CanFrame] = deque(maxlen=OUTBOX)
        self.monitor = BusMonitor()
        self.syncs = 0
        self.bus_load = 0.0
        self._load_mark = (0, 0)  # (second, busy us then)
        self._load_next_us = 1_000_000  # the first instant of the second after the mark's
        self._calm_until = 0  # quiet steps proven before this instant (_quiet); 0: none
        self._boot_at: int | None = None
        self._power_seen: object | None = None
        self._known_alarms: list[int] = []
        self._t = 0  # the instant being processed (a frame's end, or the step)
        self._canopen_od: Any = None
        # DSP 402 objects the drive model leaves to the node (0x6504, 0x6505, 0x67FF): device
        # profile, not communication profile, so a Reset communication keeps them and only a
        # power-up (Reset node included) makes them afresh (ch. 4 "Reset-Comunicazione").
        self._profile_extras = build_profile_extras()
        self._reset_communication()

    def part_of(self) -> str:
        return f"the CANopen node of {self.drive.device_id}"

    # ---- communication parameters (DS 301 Reset-Communication) ---------------------------
    def _reset_communication(self) -> None:
        self.sync_cob_id = SYNC_COB_ID
        self.cycle_period_us = 0
        self.emcy_cob_id = em.EMCY_BASE + self.node_id
        self.emcy = em.EmcyProducer()
        self.history = em.ErrorHistory()
        self.life_guard_error = False
        self.heartbeat = Heartbeat()
        self.guard = NodeGuard()
        self.rpdos = [Pdo.default(n, True, self.node_id) for n in range(1, 5)]
        self.tpdos = [Pdo.default(n, False, self.node_id) for n in range(1, 5)]
        self.dictionary = CanOpenDictionary(build_comm_objects(self), self.drive.od,
                                            self._profile_extras)
        if self._canopen_od is None:
            self._canopen_od = build_canopen_od(self.dictionary, self.node_id)
        self.sdo = SdoChannel(self.node_id, self.dictionary, self._canopen_od, self._send_now)
        self._route_rpdos()

    def _route_rpdos(self) -> None:
        """The frames the node takes as RPDOs: the COB-IDs of its valid RPDOs as they are now
        ("la validazione del corrispondente COB-ID nel OD"; bit 31 set: not taken) that map
        something: a PDO carries one to eight bytes, so with 0x160x:0 = 0 the RPDO is not in
        use, as its TPDO twin is not sent (docs/canopen.md). Made again at every write of a
        0x140x:1 or 0x160x:0, so a received frame costs one dict look-up."""
        routes: dict[int, tuple[Pdo, ...]] = {}
        for pdo in self.rpdos:
            if pdo.valid and pdo.count:
                # Two RPDOs on one COB-ID both take the frame, as two receivers would.
                routes[pdo.can_id] = (*routes.get(pdo.can_id, ()), pdo)
        self._by_rx_id = routes

    def set_pdo_cob_id(self, pdo: Pdo, value: int) -> None:
        """0x1400-0x1403:1 / 0x1800-0x1803:1. A TPDO is sent with its COB-ID as it is at
        each send; an RPDO's new COB-ID takes effect for the next frame."""
        pdo.set_cob_id(value)
        if pdo.receive:
            self._route_rpdos()

    def set_pdo_count(self, pdo: Pdo, value: int) -> None:
        """0x1600-0x1603:0 / 0x1A00-0x1A03:0: an RPDO mapped or emptied starts or stops
        taking frames."""
        pdo.set_count(value, self.dictionary.entry)
        if pdo.receive:
            self._route_rpdos()

    def set_event_timer(self, pdo: Pdo, value: int) -> None:
        """0x1800-0x1803:5, written at the instant the request crossed the bus."""
        pdo.set_event_timer(value, self._t)

    # ---- what the comm objects call -------------------------------------------------------
    @property
    def heartbeat_ms(self) -> int:
        return self.heartbeat.period_ms

    def set_heartbeat(self, period_ms: int) -> None:
        self.heartbeat.set_period(period_ms, self._t)

    def set_guard_time(self, ms: int) -> None:
        self.guard.guard_time_ms = ms
        if not ms:
            self.guard.reset()
        else:  # a new life time (0x100C x 0x100D): not measured from an older request
            self.guard.restart_life_time()

    def set_life_time_factor(self, factor: int) -> None:
        self.guard.life_time_factor = factor
        self.guard.restart_life_time()

    def clear_history(self, value: int) -> None:
        if value != 0:  # "al sub0 può essere scritto solo col valore 0"
            raise SdoAbort(AbortCode.VALUE_RANGE, 0x1003, 0)
        self.history.clear()

    @property
    def error_register(self) -> int:
        reg = 0
        if self.drive.powered:
            table = self.drive.alarm_table
            for code in self.drive.alarms.latched:
                reg |= em.register_bits(table[code].error_code_or_generic)
        if self.life_guard_error:
            reg |= em.register_bits(em.LIFE_GUARD_ERROR)
        return reg

    # ---- the bus side ----------------------------------------------------------------------
    def receive(self, can_id: int, data: bytes = b"", rtr: bool = False,
                dlc: int | None = None) -> None:
        """A frame from the bus, offered now; the node sees it once it is through the line."""
        if not self.active:
            return
        frame = CanFrame(can_id, bytes(data), rtr, dlc if rtr and dlc is not None else -1)
        self._calm_until = 0
        self.line.offer(frame, self.now_us)

    def cmd_frame(self, cob_id: int, data: str, rtr: bool) -> None:
        try:
            raw = bytes.fromhex(data)
        except ValueError:
            raise CommandError(f"data {data!r} is not hex bytes (e.g. '2B 17 10 00')") from None
        if len(raw) > 8:
            raise CommandError(f"a CAN frame carries at most 8 data bytes, got {len(raw)}")
        self.receive(cob_id, raw, rtr=rtr, dlc=len(raw) if rtr else None)

    def take_frames(self) -> list[CanFrame]:
        """The frames the node finished sending, oldest first."""
        out = list(self.outbox)
        self.outbox.clear()
        return out

    # ---- time -----------------------------------------------------------------------------
    def step(self, now_us: int) -> None:
        # DeviceModel.step, inline: the idle node's step is mostly calls (docs/canopen.md
        # "Step cost")
        if now_us < self.now_us:
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {self.now_us})")
        self.now_us = self._t = now_us
        drive = self.drive
        full = (drive.latched_at_power_up if drive.powered else None) is not self._power_seen \
            or not self.SKIP_QUIET
        if not full:
            if not self.active:  # the same power, still silent: nothing can happen
                return
            # A quiet step proved calm up to _calm_until: since then only quiet steps ran,
            # nothing was received or sent (both reset it) and time alone changes nothing
            # before that instant; the drive's alarms are the one input from outside.
            calm = now_us < self._calm_until and drive.alarms.latched == self._known_alarms
            full = not (calm or self._quiet(now_us))
        if full:
            self._full_step(now_us)
            if not self.active:
                return
        elif self.state is _OPERATIONAL:
            # The one part of a full step that may still act: the asynchronous TPDOs.
            sent = self._async_tpdos(now_us)
            if sent:
                self._wire(now_us)
        if now_us >= self._load_next_us:
            second = now_us // 1_000_000
            busy = self.line.busy_us_total
            self.bus_load = (busy - self._load_mark[1]) / 1e6
            self._load_mark = (second, busy)
            self._load_next_us = (second + 1) * 1_000_000

    # ---- quiet spans (docs/canopen.md "Quiet spans") --------------------------------------
    def quiet_until(self, step_us: int) -> int:
        """The last step instant before which every step would be a quiet one that sends
        nothing (see :meth:`DeviceModel.quiet_until`): a silent node for ever; an active
        one until its next heartbeat, the first instant its life time runs out, or the
        event timer of an asynchronous TPDO in Operational, whichever comes first. Cheap
        "no" first: the power, the line, the alarms, the emergencies; the TPDOs are packed
        last (their getters are the drive's), without touching the packing plan.

        Relies on the rig's rule that the drive is quiet over the same span (the rig skips
        only when every device says so): the drive's power (``latched_at_power_up``), its
        latched alarms and every object a TPDO maps (statusword, positions, registers) are
        what they are now at every step of the span."""
        now = self.now_us
        drive = self.drive
        if (drive.latched_at_power_up if drive.powered else None) is not self._power_seen \
                or not self.SKIP_QUIET:
            return now  # the next step runs in full (or every step does)
        end = CALM_FOREVER
        if self.active:
            if self._boot_at is not None:
                return now
            line = self.line
            if line._waiting or line._incoming or line._on_wire is not None:
                return now
            state = self.state
            if state is not NmtState.INITIALISATION:  # (Initialisation: _quiet says True)
                if drive.alarms.latched != self._known_alarms:
                    return now
                if self.emcy.pending and allows(state, Service.EMCY):
                    return now  # (held in Stopped, they wait for an NMT frame)
                beat = self.heartbeat.next_us
                if beat is not None:
                    end = beat  # the step at or after it sends the heartbeat
                expiry = self.guard.expiry_at()
                if expiry is not None and expiry < end:
                    end = expiry  # the step at or after it sends EMCY 0x8130
                if state is NmtState.OPERATIONAL and end - now > step_us:  # else no span
                    for pdo in self.tpdos:
                        if pdo.cob_id & COB_INVALID or pdo.trans_type not in ASYNC_TYPES:
                            continue
                        data = self._peek_pack(pdo)
                        if data is None:  # not packed: never sent (the drive stays as it is)
                            continue
                        if data != pdo.last_data:  # an event: sent at the next step
                            return now
                        start = pdo.timer_from_us  # set with last_data (_send_pdo)
                        if pdo.event_timer_ms and start is not None:
                            due = start + pdo.event_timer_ms * 1000  # the timer sends it
                            if due < end:
                                end = due
            # The bus-load mark: skip_to moves it exactly only when no step can jump a
            # whole second (and when it was moved at the last step, as every active step does).
            if self._load_next_us <= now:
                return now
            if step_us > SECOND_US and self._load_next_us < end:
                end = self._load_next_us
        steps = (end - 1 - now) // step_us  # the last step instant before ``end``
        return now + steps * step_us if steps > 0 else now

    def _peek_pack(self, pdo: Pdo) -> bytes | None:
        """:meth:`_pack` without a side effect: through the plan when it stands (it is then
        left as it is), else the plain :meth:`Pdo.pack` (same getters, bytes, exceptions);
        None, as from :meth:`_pack`, for a TPDO with nothing mapped."""
        if not pdo.count:
            return None
        plan = pdo._plan
        if plan is not None and plan[0] is self.dictionary and plan[1] == pdo.count \
                and plan[2] == pdo.entries:
            return self._pack(pdo)
        try:
            return pdo.pack(self.dictionary.entry, self.dictionary.peek)
        except (SdoAbort, CommandError):
            return None

    def skip_to(self, t_us: int, step_us: int) -> None:
        """As the quiet steps up to ``t_us`` would leave the node (a silent node: the clock
        only). Exact piece by piece: the calm proof a quiet step makes (``_calm_until``); the
        packing plans the asynchronous TPDOs' packs make in Operational (the data itself is
        unchanged and nothing is sent); the bus-load mark at each new second (the line is
        idle, so its busy time stays: the first new second reads the busy time since the
        mark, any later one reads 0)."""
        if self.active and t_us > self.now_us:
            state = self.state
            if state is not NmtState.INITIALISATION:
                # A step at or after _calm_until finds it past and runs _quiet, which proves
                # calm up to the heartbeat / life-guard expiry (both after t_us): as _quiet sets.
                if self._calm_until <= t_us:
                    beat, expiry = self.heartbeat.next_us, self.guard.expiry_at()
                    self._calm_until = min(CALM_FOREVER if beat is None else beat,
                                           CALM_FOREVER if expiry is None else expiry)
                if state is NmtState.OPERATIONAL:
                    dictionary = self.dictionary
                    for pdo in self.tpdos:
                        if pdo.cob_id & COB_INVALID or pdo.trans_type not in ASYNC_TYPES:
                            continue
                        plan = pdo._plan
                        if plan is None or plan[0] is not dictionary \
                                or plan[1] != pdo.count or plan[2] != pdo.entries:
                            self._pack(pdo)  # the plan the first quiet step would make
            if t_us >= self._load_next_us:
                second = t_us // SECOND_US
                busy = self.line.busy_us_total
                crossed_one = second * SECOND_US == self._load_next_us
                self.bus_load = (busy - self._load_mark[1]) / 1e6 if crossed_one \
                    else (busy - busy) / 1e6
                self._load_mark = (second, busy)
                self._load_next_us = (second + 1) * SECOND_US
        self.now_us = self._t = t_us

    def _full_step(self, now_us: int) -> None:
        self._calm_until = 0
        self._follow_power(now_us)
        if not self.active:
            return
        if self._boot_at is not None and now_us >= self._boot_at:
            self._boot(self._boot_at)
        self._wire(now_us)
        if self.state is not NmtState.INITIALISATION:
            self._timers(now_us)
        self._wire(now_us)

    def _quiet(self, now_us: int) -> bool:
        """True when every part of a full step but the asynchronous TPDOs would find nothing
        to do at ``now_us`` for an active node (the caller checked the power): no boot due,
        nothing on or for the line, no heartbeat, life-guard expiry, alarm change or
        emergency due. Skipping those parts is exact (the idle node costs a few reads;
        docs/canopen.md "Step cost"); in Operational the step still runs the asynchronous
        TPDOs, as a full step would (:meth:`_async_tpdos`)."""
        if self._boot_at is not None:
            return False
        line = self.line
        if line._waiting or line._incoming or line._on_wire is not None:  # not line.idle
            return False
        if self.state is NmtState.INITIALISATION:
            return True
        beat = self.heartbeat.next_us
        if beat is not None and beat <= now_us:
            return False
        guard = self.guard
        if guard.last_request_us is not None and guard.expires_by(now_us):
            return False
        if self.drive.alarms.latched != self._known_alarms:
            return False
        if self.emcy.pending and allows(self.state, Service.EMCY):
            return False  # held in Stopped, they wait for an NMT frame (receive ends calm)
        # Quiet: and so until the heartbeat or the life guarding falls due, unless a frame
        # comes or goes or a full step runs first (step, receive and _send see to that).
        expiry = self.guard.expiry_at()
        self._calm_until = min(CALM_FOREVER if beat is None else beat,
                               CALM_FOREVER if expiry is None else expiry)
        return True

    def _follow_power(self, now_us: int) -> None:
        seen = self.drive.latched_at_power_up if self.drive.powered else None
        if seen is self._power_seen:
            return
        self._power_seen = seen
        self.line.clear()
        self._known_alarms = []
        was_active, self.active = self.active, False
        if seen is not None and self.drive.fieldbus == "canopen":
            self.active = True
            self.node_id = self.drive.node_id
            self.bitrate = bitrate_of_n1(self.drive.latched_at_power_up["n1"])
            self.line = CanLine(self.bitrate, busy_until_us=now_us)
            self._profile_extras = build_profile_extras()
            self._enter_initialisation(now_us, now_us + BOOT_US)
        elif was_active:  # powered off, or c9 no longer CANopen: silent from now on
            # Reported like every NMT change (the recording's lane and the event log follow
            # it): back to the power-on state, as the DS402 machine and the CoE ESM go.
            self._set_state(NmtState.INITIALISATION, now_us)
            self._boot_at = None

    def _enter_initialisation(self, t: int, boot_at: int) -> None:
        self._set_state(NmtState.INITIALISATION, t)
        self._reset_communication()
        # The EMCY producer starts over as at power-up: an alarm still latched is an active
        # error the node reports again after its boot-up (docs/canopen.md §Emergencies).
        self._known_alarms = []
        self._boot_at = boot_at

    def _boot(self, t_us: int) -> None:
        """End of Initialisation: the boot-up message, then Pre-operational."""
        self._boot_at = None
        self._t = t_us
        self._send(HEARTBEAT_BASE + self.node_id, bytes((BOOT_UP_CODE,)), t_us)
        self._set_state(NmtState.PRE_OPERATIONAL, t_us)
        if self.heartbeat.period_ms:
            self.heartbeat.set_period(self.heartbeat.period_ms, t_us)

    def _wire(self, now_us: int) -> None:
        while (frame := self.line.next_done(now_us)) is not None:
            self._log(frame)
            if frame.rx:
                self._t = frame.t_us
                self._handle(frame)
            else:
                self.outbox.append(frame)

    def _timers(self, now_us: int) -> None:
        self._t = now_us
        at = self.heartbeat.due(now_us)
        if at is not None and allows(self.state, Service.GUARDING):
            self._send(HEARTBEAT_BASE + self.node_id, bytes((self.state.code,)), at)
        expired = self.guard.check(now_us)
        if expired is not None:
            self.life_guard_error = True  # "L'EMCY non viene resettato"
            self._emergency(em.LIFE_GUARD_ERROR, b"", expired)
        self._watch_alarms(now_us)
        # In Stopped they wait: the error event is owed until the node may speak (_set_state)
        while allows(self.state, Service.EMCY) and (due := self.emcy.due(now_us)) is not None:
            data, at = due
            self._send(self.emcy_cob_id & 0x7FF, data, at)
            self.emit(EmergencySent(at, self.drive.device_id, code=int.from_bytes(data[:2],
                      "little"), register=data[2], data=data[3:]))
        if self.state is NmtState.OPERATIONAL:
            self._async_tpdos(now_us)

    # ---- received frames -------------------------------------------------------------------
    def _handle(self, frame: CanFrame) -> None:
        can_id, data, t = frame.can_id, frame.data, frame.t_us
        if self.state is NmtState.INITIALISATION:
            return
        if can_id == NMT_COB_ID and not frame.rtr:
            command = parse_command(data, self.node_id)
            if command is not None:
                self._nmt(command, t)
        elif can_id == HEARTBEAT_BASE + self.node_id and frame.rtr:
            self._guard_request(t)
        elif frame.rtr:
            self._pdo_request(can_id, t)
        elif can_id == SDO_RX_BASE + self.node_id and allows(self.state, Service.SDO):
            self.sdo.on_request(data)
        elif can_id == self.sync_cob_id & 0x7FF and allows(self.state, Service.SYNC):
            self._sync(t)
        elif can_id in self._by_rx_id and allows(self.state, Service.PDO):
            for pdo in self._by_rx_id[can_id]:
                self._rpdo(pdo, data, t)

    def _nmt(self, command: NmtCommand, t: int) -> None:
        new = next_state(self.state, command)
        if new is None:
            return
        if command is NmtCommand.RESET_NODE:
            # Reset-Application: profile and manufacturer values back to their power-on
            # values (the last saved ones): the drive restarts as at power-up.
            self.drive.apply("power", {"on": False})
            self.drive.apply("power", {"on": True})
            self._follow_power(t)
        elif command is NmtCommand.RESET_COMMUNICATION:
            self._enter_initialisation(t, t + RESET_COMMUNICATION_US)
        else:
            self._set_state(new, t)

    def _set_state(self, new: NmtState, t: int) -> None:
        old, self.state = self.state, new
        if old is new:
            return
        self.emit(StateChanged(t, self.drive.device_id, from_state=old.label,
                               to_state=new.label, machine="nmt"))
        if new is NmtState.OPERATIONAL:
            for pdo in (*self.rpdos, *self.tpdos):
                pdo.restart()
        if allows(new, Service.EMCY) and not allows(old, Service.EMCY):
            self.emcy.release(t)  # what Stopped held leaves now (docs/canopen.md §Emergencies)

    def _guard_request(self, t: int) -> None:
        self.guard.request(t)
        bit = self.guard.answer_bit(self.heartbeat.period_ms != 0)
        if bit is not None:
            self._send(HEARTBEAT_BASE + self.node_id, bytes((self.state.code | bit,)), t)

    def _emergency(self, code: int, vendor: bytes, t: int, transient: bool = False,
                   info: int = 0) -> None:
        if code != em.ERROR_RESET:
            self.history.record(code, info)
        register = self.error_register | (em.register_bits(code) if transient else 0)
        if not self.emcy_cob_id & 0x8000_0000:  # queued in Stopped too: held, see _timers
            self.emcy.queue(em.payload(code, register, vendor), t)

    def _watch_alarms(self, now_us: int) -> None:
        """A newly latched alarm -> EMCY with its 0x603F code; none left -> error reset."""
        latched = list(self.drive.alarms.latched)
        table = self.drive.alarm_table
        for code in latched:
            if code not in self._known_alarms:
                self._emergency(table[code].error_code_or_generic, bytes((code,)), now_us,
                                info=code)
        if self._known_alarms and not latched:
            self._emergency(em.ERROR_RESET, b"", now_us)
        self._known_alarms = latched

    def _send(self, can_id: int, data: bytes, t: int) -> None:
        self._calm_until = 0
        self.line.offer(CanFrame(can_id, data, rx=False), t)

    def _send_now(self, can_id: int, data: bytes) -> None:
        """SDO answers: at the instant the request finished."""
        self._send(can_id, data, self._t)

    # ---- views ----------------------------------------------------------------------------
    def _log(self, frame: CanFrame) -> None:
        pdos = (*self.rpdos, *self.tpdos)
        self.monitor.record(frame, Context(sync_id=self.sync_cob_id & 0x7FF,
                                           pdo_text=lambda i, d: pdo_text(pdos, i, d),
                                           emcy_text=self._emcy_text))

    def _emcy_text(self, can_id: int, code: int, vendor: bytes) -> str | None:
        """This node's EMCY carries a drive alarm, its number a hex byte: "alarm 16 ..." in
        the drive's decimal numbering (ch. 3). Another node's bytes are its own to mean."""
        if can_id != self.emcy_cob_id & 0x7FF:
            return None
        alarm = alarm_in_emergency(code, vendor, self.drive.fieldbus)
        return f"alarm {alarm.code} {alarm.name}" if alarm else None

    def snapshot(self) -> dict[str, Any]:
        return {
            "kind": self.KIND, "drive": self.drive.device_id, "active": self.active,
            "node_id": self.node_id, "bitrate": self.bitrate,
            "nmt": self.state.label if self.active else NO_STATE,
            "heartbeat_ms": self.heartbeat.period_ms,
            "guard_time_ms": self.guard.guard_time_ms,
            "life_time_factor": self.guard.life_time_factor,
            "life_guard_error": self.life_guard_error,
            "error_register": self.error_register if self.active else 0,
            "error_history": ([error_field_text(self.history.latest, self.drive.alarm_table)]
                              if self.history.count else []),
            "sync_cob_id": f"0x{self.sync_cob_id:08X}", "emcy_cob_id": f"0x{self.emcy_cob_id:08X}",
            "rpdo": [p.describe() for p in self.rpdos],
            "tpdo": [p.describe() for p in self.tpdos],
            "last_sdo": self.monitor.last_sdo, "last_pdo": self.monitor.last_pdo,
            "last_sdo_exchange": {"request": self.monitor.sdo_request,
                                  "response": self.monitor.sdo_response},
            "frames": self.monitor.recent(FRAMES_IN_SNAPSHOT),
            "heartbeats": self.monitor.heartbeats(),
            "bus": {**self.monitor.counts, "syncs": self.syncs,
                    "load": round(self.bus_load, 4), "dropped": self.line.dropped},
        }

