"""The servo drive's EtherCAT side: a CoE slave in the rig's EtherCAT line (seed 004 ch. 5).

``DriveEcatSlave`` wraps a :class:`~devices.servo.drive.ServoDrive` and is a slave of
:class:`devices.master.EtherCatMaster` (the ``Slave`` protocol). It is on the line only while
the drive is powered and c9 was 11 (EtherCAT) at the drive's power-up ("Parametro drive C9 =
11 (modalità ethercat)"; no node number: "è lo stesso ethercat che definisce l'indirizzamento").
Stepped after its drive and before the master, like the CANopen node.

- ESM (devices/coe/esm.py): mailbox from PREOP, the PDO assignment checked at PREOP -> SAFEOP
  (a bad one refuses with 0x0025 / 0x0024 and raises the drive's alarm 33 "mappatura pdo non
  eseguita correttamente"; an injected 33 refuses with 0x0025 until cleared), outputs needed
  for SAFEOP -> OP, no BOOT.
- Process data: the master's frame (``exchange_frame``) carries the outputs image a PLC set
  with ``write_outputs``; it is applied in OP only, through the same object dictionary as an
  SDO, and it is the drive's Sync (SM-Synchron). Inputs are valid from SAFEOP. No frame for
  the SM watchdog time in OP: back to SAFEOP with 0x001B and alarm 34 (sync timeout); an
  injected 34 does the same, and refuses SAFEOP -> OP with 0x001B until cleared.
- A drive alarm of its controller (7, 30-32: esm.CONTROLLER_ALARMS) takes the process data
  away: SAFEOP / OP -> PREOP with 0x002B, SAFEOP refused until the alarm is reset; the
  mailbox goes on. Alarm 35 (the EtherCAT EEPROM, esm.EEPROM_ALARM) is a booting error:
  INIT + error with 0x0051, PREOP refused until the alarm is reset (ERR flickering, ETG.1300).
  Any other drive alarm is the CiA 402 Fault only (ETG.6010): OP stays.
- Mailbox: SDO upload / download / info over the dictionary of devices/coe/objects.py;
  emergencies with the 0x603F codes (8-byte frames).

Its events carry the drive's device id (ESM moves with ``machine: "esm"``, AL status codes,
emergencies, LEDs), as the CANopen node's do. Choices: docs/ethercat-coe.md.
"""

from __future__ import annotations

import logging
import random
from collections import deque
from collections.abc import Mapping
from typing import Any, ClassVar

from devices.canopen.dictionary import CanOpenDictionary
from devices.canopen.pdo import split_entry
from devices.coe import process_image
from devices.coe.actions import ACTIONS, SlaveActions
from devices.coe.assignment import Assignment, assigned_pdos, default_pdos, mapping_problem
from devices.coe.csp import Csp
from devices.coe.emergency import EmergencyMailbox
from devices.coe.esm import (
    EEPROM_ALARM,
    EEPROM_ERROR,
    INVALID_INPUT_MAPPING,
    INVALID_OUTPUT_MAPPING,
    NO_VALID_INPUTS_AND_OUTPUTS,
    NO_VALID_OUTPUTS,
    RANK,
    REFUSAL_KIND,
    SM_WATCHDOG,
    TRANSITION_CHECKS,
    ErrorKind,
    Esm,
    controller_alarm,
    request_refusal,
)
from devices.coe.leds import LedInputs, alarm_led, wanted_patterns
from devices.coe.mailbox import SdoServices
from devices.coe.objects import build_coe_dictionary
from devices.coe.sm_checks import SmChecks
from devices.device import Action, CommandError, DeviceModel
from devices.esm import AlStatusView, first_refusal
from devices.ethercat import AlState, describe_al_status_code
from devices.events import EmergencySent
from devices.leds import LedPattern
from devices.od import IEC_NAMES, OdEntry, SdoAbort, TypeNames
from devices.servo.drive import ServoDrive
from devices.sync_managers import SmSetup

logger = logging.getLogger(__name__)

ETHERCAT = "ethercat"  # drive.fieldbus for c9 = 11
BOX_NAME = "Drive 1 (SelemaDriveECAT)"  # TwinCAT's name for it (ch. 5: "Drive 5 (Selema...)")
SM_WATCHDOG_US = 100_000  # ESC default SM watchdog (0x0420 = 1000 x 100 us)
# Esm.at_least(SAFEOP) as a set (every state has a rank), for the per-cycle exchange_frame
SAFEOP_OR_HIGHER = frozenset(s for s, rank in RANK.items() if rank >= RANK[AlState.SAFEOP])
ACTIVITY_WINDOW_US = 50_000  # L/A flickers while a frame passed this recently
MAPPING_ALARM = 33  # ch. 5: "Errore mappatura pdo non eseguita correttamente"
SYNC_TIMEOUT_ALARM = 34  # ch. 5: "Timeout sincronizzazione con il Master ECAT"
QUICK_STOP = 0x0002  # ch. 4 "rilascio asse": the drive stops and leaves torque
SDO_LOG = 20
# quiet_until's answer when nothing in the slave itself ends the span (whole steps past it)
QUIET_FOREVER_STEPS = 1 << 40
OFF = "Off"  # the slave is not on the line (drive off, or c9 != 11)
OFF_LED = LedPattern.OFF
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_PREOP, _OP = AlState.PREOP, AlState.OP


class DriveEcatSlave(SlaveActions, SdoServices, SmChecks, AlStatusView, DeviceModel):
    KIND = "servo_ecat"
    ACTIONS: ClassVar[Mapping[str, Action]] = ACTIONS
    # Seed 004 §5.5's TwinCAT Process Data list prints the IEC names (604100 Status Word UINT,
    # 606400 Position Actual Value DINT), seed 000's words (docs/ethercat-coe.md).
    TYPE_NAMES: ClassVar[TypeNames] = IEC_NAMES

    def __init__(self, device_id: str, drive: ServoDrive, rng: random.Random | None = None,
                 box_name: str = BOX_NAME, station_address: int = 1001,
                 out_link: bool = False) -> None:
        super().__init__(device_id=device_id, rng=rng or random.Random(0))
        self.drive = drive
        self.box_name = box_name
        self.station_address = station_address
        self.serial = self.rng.getrandbits(32)
        self.link = True
        # Each port's link: the line's cable there (line_in / line_out, the master's set_link;
        # OUT: a next slave cabled and powered, none when last on the line) and the
        # operator's own plug (plugs: IN, OUT; the master folds them into its line model).
        self.line_in, self.plugs = True, (True, True)
        self.line_out = self.link_out = out_link
        self.on_line = False
        self.esc = False  # powered: the ESC has its ports' links and passes frames, any c9
        self.sm_setup: tuple[SmSetup, ...] | None = None  # a master on the wire wrote them
        self.emergencies = EmergencyMailbox()
        self.esm = Esm(self.emit, drive.device_id, stop_mailbox=self.emergencies.stop,
                       leave_op=self._leave_op)  # also when a request is refused in OP
        self.csp = Csp(drive)
        self.leds = drive.network_leds  # on the drive's front; this slave drives them
        self.sdo_log: deque[dict[str, Any]] = deque(maxlen=SDO_LOG)
        self._led_inputs: LedInputs | None = None
        self._power_seen: object | None = None
        self._reset()
        self._follow_power()
        self._refresh()

    def part_of(self) -> str:
        return f"the EtherCAT CoE slave of {self.drive.device_id}"

    def _reset(self) -> None:
        """Power-on values of the EtherCAT side."""
        self.rx_pdos, self.tx_pdos = default_pdos(True), default_pdos(False)
        self.rx_assign, self.tx_assign = Assignment.default(True), Assignment.default(False)
        self.csp.selected = False
        self.emergencies.reset()
        self.last_frame_us: int | None = None
        self.outputs: bytes | None = None  # the image the master's PLC writes
        self.applied: bytes | None = None  # the last image applied to the drive
        self.inputs: bytes | None = None
        self._inputs_due = False  # a frame passed since the inputs were last packed
        self.pd_control = False  # outputs applied since OP was entered
        self.frames = 0
        self.dictionary: CanOpenDictionary = build_coe_dictionary(self)

    @property
    def od(self) -> CanOpenDictionary:
        """What the object-dictionary view lists (the dictionary a CoE master sees)."""
        return self.dictionary

    def dictionary_entry(self, index: int, sub: int) -> OdEntry:
        return self.dictionary.entry(index, sub)

    # ---- the master's side (devices.master.Slave) ---------------------------------------------
    def reachable(self) -> bool:
        return self.on_line and self.link

    def set_link(self, connected: bool, port: str = "in") -> None:
        """A cable on port IN (from the master's side) or OUT (to the next slave)."""
        if port == "in":
            self.line_in = connected
            self.link = connected and self.plugs[0]
        else:
            self.line_out = connected
            self.link_out = connected and self.plugs[1]

    def set_power(self, on: bool) -> None:
        """The drive's own supply: its EtherCAT side follows it."""
        self.drive.apply("power", {"on": on})

    @property
    def powered(self) -> bool:
        return bool(self.drive.powered)

    def request_state(self, target: AlState, ack: bool = False) -> None:
        """AL control write; the answer is in ``al_status`` / ``al_status_code``."""
        if not self.reachable():
            return
        now, esm, current = self.now_us, self.esm, self.esm.state
        if not esm.take_request(target, ack, now):  # bit 4 "Error Ind Ack" (ETG.1000.6)
            return
        esm.requested = target
        refusal = request_refusal(current, target)
        if refusal is not None:
            esm.refuse(refusal, now)
        elif target is current or RANK[target] < RANK[current]:
            if current is AlState.OP and target is not AlState.OP:
                self._leave_op()
            esm.accept(target, now)
            if not esm.at_least(AlState.SAFEOP):
                self.inputs, self._inputs_due = None, False
        else:
            code = first_refusal(self, TRANSITION_CHECKS, current, target)
            if code is not None:
                esm.refuse(code, now, REFUSAL_KIND.get(code))
            else:
                self._enter(target)
        esm.settle_request(now)
        self._refresh()

    def take_emergencies(self) -> list[bytes]:
        """8-byte CoE emergencies (code LE16, register, 5 bytes); the mailbox runs from PREOP."""
        if not self.emergencies.pending:  # the master asks every cycle: nothing to hand over
            return []
        if not self.reachable() or not self.esm.at_least(AlState.PREOP):
            return []
        return self.emergencies.take()

    def exchange_frame(self, now_us: int) -> None:
        """One cyclic frame of the master passed (the SM2 / SM3 events)."""
        if not (self.on_line and self.link):  # reachable(), inline: called every cycle
            return
        self.last_frame_us = now_us
        self.frames += 1
        state = self.esm.state
        if state is _OP and self.outputs is not None:
            self._apply_outputs(self.outputs)
            state = self.esm.state
        self._inputs_due = state in SAFEOP_OR_HIGHER if state in RANK \
            else self.esm.at_least(AlState.SAFEOP)

    def frame_passed(self, now_us: int) -> None:
        """A frame of the master crossed the ESC of a slave that does not answer (c9 != 11 at
        the drive's power-up): the ESC forwards it and its L/A show the traffic (ETG.1300 L/A
        are the ESC's); the application takes nothing from it. The master calls this for a
        silent slave on the frames' path only (docs/ethercat-coe.md "LEDs of a drive with
        c9 != 11")."""
        if self.esc and self.link and not self.on_line:
            self.last_frame_us = now_us

    # ---- process data ----------------------------------------------------------------------
    @property
    def rx_assigned(self) -> list:
        return assigned_pdos(self.rx_assign, self.rx_pdos)

    @property
    def tx_assigned(self) -> list:
        return assigned_pdos(self.tx_assign, self.tx_pdos)

    def write_outputs(self, data: bytes) -> None:
        """The outputs image the master sends from its next frame on (the PLC's variables)."""
        expected = process_image.size(self.rx_assigned)
        if len(data) != expected:
            raise CommandError(f"the outputs image of '{self.box_name}' is {expected} bytes "
                               f"(0x1C12: {self._names(self.rx_assign)}), got {len(data)}")
        self.outputs = bytes(data)

    def read_inputs(self) -> bytes | None:
        """The inputs image of the last frame; None below SAFEOP (no valid inputs).

        Packed when read, once per frame: the statusword costs about what a drive step does,
        and the rig's readers (a PLC, the panel) read between steps, at the frame's instant.
        """
        if not (self.reachable() and self.esm.at_least(AlState.SAFEOP)):
            return None
        if self._inputs_due:
            self._inputs_due = False
            self.inputs = self._pack_inputs()
        return self.inputs

    def cycle(self, outputs: bytes | None, now_us: int) -> bytes | None:
        """One master cycle: outputs in (None = keep the image), frame, inputs out."""
        if outputs is not None:
            self.write_outputs(outputs)
        self.exchange_frame(now_us)
        return self.read_inputs()

    def _apply_outputs(self, data: bytes) -> None:
        lookup = self.dictionary.entry
        writes = process_image.last_writes(process_image.unpack(self.rx_assigned, data, lookup))
        for index, sub, value in writes:
            try:
                self.dictionary.write(index, sub, value)
            except SdoAbort as exc:
                logger.info("%s: output 0x%04X:%d not applied: %s", self.drive.device_id, index,
                            sub, exc)
        self.applied, self.pd_control = data, True
        if self.drive.mode == 7 and self.drive.responding:  # interpolated or CSP: SM-Synchron
            self.drive.apply("sync", {})

    def _pack_inputs(self) -> bytes | None:
        try:
            return process_image.pack(self.tx_assigned, self.dictionary.entry,
                                      self.dictionary.peek)
        except (SdoAbort, CommandError) as exc:
            logger.debug("%s: inputs not packed: %s", self.drive.device_id, exc)
            return None

    def configuration_changed(self) -> None:
        """A PDO mapping or assignment changed (PREOP): the images start over."""
        self.outputs = self.applied = self.inputs = None
        self._inputs_due = False

    # ---- ESM ----------------------------------------------------------------------------------
    def check_output_mapping(self) -> int | None:
        if MAPPING_ALARM in self.drive.alarms.injected:
            # An injected 33 is a mapping fault in the drive: any mapping fails its check, on
            # the RxPDO side, checked first (docs/ethercat-coe.md "Injected 33 and 34")
            return self._refuse_mapping(f"alarm {MAPPING_ALARM} persists",
                                        INVALID_OUTPUT_MAPPING)
        return self._check_mapping(self.rx_assign, self.rx_pdos, INVALID_OUTPUT_MAPPING)

    def check_input_mapping(self) -> int | None:
        return self._check_mapping(self.tx_assign, self.tx_pdos, INVALID_INPUT_MAPPING)

    def _check_mapping(self, assignment: Assignment, pdos: list, code: int) -> int | None:
        problem = mapping_problem(assignment, pdos)
        if problem is None:
            return None
        return self._refuse_mapping(problem, code)

    def _refuse_mapping(self, problem: str, code: int) -> int:
        if self.esm.code != code:  # one message per refusal episode, not per retry
            self.drive.log(f"EtherCAT: PDO mapping refused at PREOP -> SAFEOP: {problem}")
        self.drive.raise_alarm(MAPPING_ALARM, lasting=True)
        return code

    def check_controller(self) -> int | None:
        """No step up to process data while the drive's controller is in alarm."""
        if controller_alarm(self.drive.alarms.latched) is None:
            return None
        return NO_VALID_INPUTS_AND_OUTPUTS

    def check_eeprom(self) -> int | None:
        """No PREOP while the EtherCAT EEPROM alarm is latched (a booting error)."""
        return EEPROM_ERROR if EEPROM_ALARM in self.drive.alarms.latched else None

    def check_sync(self) -> int | None:
        """SAFEOP -> OP: no OP while an injected sync timeout (alarm 34) stands."""
        return SM_WATCHDOG if SYNC_TIMEOUT_ALARM in self.drive.alarms.injected else None

    def check_outputs(self) -> int | None:
        """SAFEOP -> OP: the master must be sending process data (SM2) already."""
        if not self.rx_assigned:
            return None
        last = self.last_frame_us
        return NO_VALID_OUTPUTS if last is None or self.now_us - last > SM_WATCHDOG_US else None

    def _enter(self, target: AlState) -> None:
        if target is AlState.SAFEOP:
            self.drive.alarms.condition_gone(MAPPING_ALARM)  # a valid mapping passed
            self._inputs_due = True
        if target is AlState.OP:
            self.pd_control = False
        self.esm.accept(target, self.now_us)

    def _leave_op(self) -> None:
        """Outputs go to their safe state: a drive under process-data control stops."""
        if self.pd_control and self.drive.responding:
            try:
                self.dictionary.write(0x6040, 0, QUICK_STOP)
            except SdoAbort as exc:
                logger.info("%s: quick stop on leaving OP refused: %s", self.drive.device_id, exc)
        self.pd_control = False

    def _check_watchdog(self) -> None:
        if self.esm.state is not AlState.OP:
            return
        last = self.last_frame_us
        if last is not None and self.now_us - last <= SM_WATCHDOG_US:
            return  # checked before the assignment: building rx_assigned costs a list a step
        if not self.rx_assigned:
            return
        self.drive.log("EtherCAT: SM watchdog expired (no process data): OP -> SAFEOP")
        self.drive.raise_alarm(SYNC_TIMEOUT_ALARM)
        self._sync_lost()

    def _check_injected_sync(self) -> None:
        """OP with an injected alarm 34: the sync timeout it names, the watchdog's own fall
        (docs/ethercat-coe.md "Injected 33 and 34"); the alarm is latched already."""
        if self.esm.state is not AlState.OP \
                or SYNC_TIMEOUT_ALARM not in self.drive.alarms.injected:
            return
        self.drive.log(f"EtherCAT: alarm {SYNC_TIMEOUT_ALARM}: sync with the master lost "
                       f"(0x{SM_WATCHDOG:04X}): OP -> SAFEOP")
        self._sync_lost()

    def _sync_lost(self) -> None:
        self._leave_op()
        self.esm.fall(AlState.SAFEOP, SM_WATCHDOG, ErrorKind.WATCHDOG, self.now_us)

    def _check_controller(self) -> None:
        """SAFEOP / OP with a controller alarm latched: no valid process data, back to PREOP."""
        if self.esm.state not in SAFEOP_OR_HIGHER:
            return
        code = controller_alarm(self.drive.alarms.latched)
        if code is None:
            return
        self.drive.log(f"EtherCAT: alarm {code}: no valid inputs and outputs (0x002B): "
                       f"{self.esm.state.label} -> PREOP")
        if self.esm.state is AlState.OP:
            self._leave_op()
        # a local error (ETG.1300 single flash); the latched alarm lights ERR on over it
        self.esm.fall(AlState.PREOP, NO_VALID_INPUTS_AND_OUTPUTS, ErrorKind.LOCAL, self.now_us)
        self.inputs, self._inputs_due = None, False

    def _booting_due(self) -> bool:
        """Alarm 35 latched and the slave not yet in INIT with its booting error."""
        return EEPROM_ALARM in self.drive.alarms.latched and not (
            self.esm.state is AlState.INIT and self.esm.error is ErrorKind.BOOTING)

    def _booting_error(self) -> None:
        """Alarm 35: the slave is in INIT + error, 0x0051, as after an EEPROM that did not
        load (ETG.1300 booting error). After the emergency watch of the same step: its
        0x5530 is in 0x1003, the mailbox stops on the way to INIT (devices/esm.py)."""
        state = self.esm.state
        if state is not AlState.INIT:
            self.drive.log(f"EtherCAT: alarm {EEPROM_ALARM}: EEPROM error (0x{EEPROM_ERROR:04X}): "
                           f"{state.label} -> INIT")
        if state is AlState.OP:
            self._leave_op()
        self.esm.fall(AlState.INIT, EEPROM_ERROR, ErrorKind.BOOTING, self.now_us)
        self.inputs, self._inputs_due = None, False

    # ---- time ---------------------------------------------------------------------------------
    def step(self, now_us: int) -> None:
        # DeviceModel.step, _follow_power's and _check_watchdog's first tests and _refresh's
        # same-inputs test inline: an idle slave's step is mostly calls (docs/ethercat-coe.md
        # "Step cost")
        if now_us < self.now_us:
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {self.now_us})")
        self.now_us = now_us
        drive = self.drive
        if (drive.latched_at_power_up if drive.powered else None) is not self._power_seen:
            self._follow_power()
        if self.on_line:
            last = self.last_frame_us
            if self.esm.state is _OP and (last is None or now_us - last > SM_WATCHDOG_US):
                self._check_watchdog()
            if drive.alarms.latched:  # empty in the usual case
                self._check_controller()
                self._check_injected_sync()
            # watch() only when the latched alarms differ from the ones it saw (cheap check)
            seen = drive.alarms.latched if drive.powered else []
            if seen != self.emergencies.known and self.esm.at_least(_PREOP):
                for frame in self.emergencies.watch(drive):
                    self.emit(EmergencySent(now_us, self.drive.device_id,
                                            code=int.from_bytes(frame[:2], "little"),
                                            register=frame[2], data=frame[3:]))
            if drive.alarms.latched and self._booting_due():
                self._booting_error()
        # _refresh() when its inputs may differ from the last ones (its own first test)
        last, esm, old, on_line = self.last_frame_us, self.esm, self._led_inputs, self.on_line
        if old is None or old.activity is not (last is not None
                                               and now_us - last <= ACTIVITY_WINDOW_US) \
                or old.state is not esm.state or old.on_line is not on_line \
                or old.link is not self.link or old.link_out is not self.link_out \
                or old.error is not esm.error \
                or old.drive_alarm is not (alarm_led(drive.alarms.latched)
                                           if on_line else OFF_LED):
            self._refresh()

    # ---- quiet spans (docs/ethercat-coe.md "Quiet spans") -------------------------------------
    # This relies on the contract's rule that the other models of the rig are quiet over the
    # same span: the drive's ``powered``, ``latched_at_power_up``, ``alarms.latched`` and
    # ``responding`` stay as they are (a drive's quiet step moves none of them).
    def quiet_until(self, step_us: int) -> int:
        """The steps up to the returned time would each take step()'s short way: the drive's
        power as last followed, no watchdog check that can fire, no emergency to send, the LED
        inputs as last refreshed. What ends a span without frames: the L/A activity window
        (last frame + 50 ms, then the LED would stop flickering) and, in OP with RxPDOs
        assigned, the SM watchdog (last frame + 100 ms). With frames (frames_quiet) neither
        moves. The early-outs come first, the cheap ones first."""
        now = self.now_us
        old = self._led_inputs
        if old is None:
            return now
        drive, esm, on_line = self.drive, self.esm, self.on_line
        if (drive.latched_at_power_up if drive.powered else None) is not self._power_seen:
            return now  # the next step follows the power
        state, last = esm.state, self.last_frame_us
        # the next step's _refresh(): every input as last refreshed, activity as at that step
        activity = last is not None and now + step_us - last <= ACTIVITY_WINDOW_US
        if old.activity is not activity or old.state is not state \
                or old.on_line is not on_line or old.link is not self.link \
                or old.link_out is not self.link_out or old.error is not esm.error \
                or old.drive_alarm is not (alarm_led(drive.alarms.latched)
                                           if on_line else OFF_LED):
            return now
        # Without frames the activity input flips at the first step past last + 50 ms: the
        # span ends at the last step on or before it (frames would keep it, as they would
        # keep everything else here). Not active: without frames it stays so.
        end = last + ACTIVITY_WINDOW_US if last is not None and activity else None
        if on_line:
            if state is AlState.OP and not activity:  # active: the window ends it sooner
                if last is None or now + step_us - last > SM_WATCHDOG_US:
                    if self.rx_assigned:
                        return now  # the next step's watchdog check fires
                elif self.rx_assigned:
                    end = last + SM_WATCHDOG_US  # the watchdog fires at the step after it
            if state is AlState.OP and SYNC_TIMEOUT_ALARM in drive.alarms.injected:
                return now  # the next step falls to SAFEOP (an injected alarm 34)
            seen = drive.alarms.latched if drive.powered else []
            if seen != self.emergencies.known and esm.at_least(AlState.PREOP):
                return now  # the next step watches the alarms (emergencies)
            if seen and self._booting_due():
                return now  # the next step takes the slave to INIT (alarm 35)
        if end is None:
            return now + QUIET_FOREVER_STEPS * step_us
        return now + max(0, (end - now) // step_us) * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        """A quiet step moves nothing but the clock (its short way through step())."""
        if t_us < self.now_us:
            raise ValueError(f"{self.device_id}: time went backwards ({t_us} < {self.now_us})")
        self.now_us = t_us

    def frames_quiet(self) -> bool:
        """Whether a frame now, and more of them while the slave's steps stay quiet, would
        change nothing but what skip_frames sets. Not: in OP with an outputs image, every frame
        writes it to the drive (0x6040 through the drive's controlword path, which touches
        the drive, sets Ien_cmd and its source, evaluates the CiA 402 state machine and the
        mode's controlword hook; 0x60C1:1 / 0x607A / 0x60FF / 0x6060; a Sync restarting the
        interpolation period in mode 7), so no frame of it is a no-op; and while the L/A
        activity input is off, a frame turns it on at the next step (the LED flickers)."""
        if not (self.on_line and self.link):
            return True  # exchange_frame returns at once
        if self.emergencies.pending or (
                self.outputs is not None and self.esm.state is AlState.OP):
            return False  # the master's mailbox read would take something
        old = self._led_inputs
        return old is not None and old.activity

    def skip_frames(self, n: int, last_us: int) -> None:
        """As ``n`` frames, the last at ``last_us`` (frames_quiet() held): the count, the time
        of the last one, the inputs due again from SAFEOP on. A frame draws nothing."""
        if n <= 0 or not (self.on_line and self.link):
            return
        state = self.esm.state
        if state is AlState.OP and self.outputs is not None:
            raise RuntimeError(f"{self.device_id}: frames in OP with outputs are not quiet")
        self.last_frame_us = last_us
        self.frames += n
        self._inputs_due = state in SAFEOP_OR_HIGHER if state in RANK \
            else self.esm.at_least(AlState.SAFEOP)

    def _follow_power(self) -> None:
        """On the line while the drive is powered with c9 = 11 latched at its power-up."""
        seen = self.drive.latched_at_power_up if self.drive.powered else None
        if seen is self._power_seen:
            return
        self._power_seen = seen
        if self.on_line or self.esm.state is not AlState.INIT:
            self.esm.reset(self.now_us)
        if self.esc is not (seen is not None):
            # the next refresh draws afresh: the step's same-inputs test leaves ``esc`` out
            # (it moves with the power only, here)
            self.esc, self._led_inputs = seen is not None, None
        self.on_line = self.esc and self.drive.fieldbus == ETHERCAT
        self._reset()

    # ---- views --------------------------------------------------------------------------------
    def _refresh(self) -> None:
        now = self.now_us
        activity = self.last_frame_us is not None and now - self.last_frame_us <= \
            ACTIVITY_WINDOW_US
        on_line, esm = self.on_line, self.esm
        drive_alarm = alarm_led(self.drive.alarms.latched) if on_line else OFF_LED
        old = self._led_inputs
        if old is not None and old.activity is activity and old.state is esm.state \
                and old.on_line is on_line and old.esc is self.esc and old.link is self.link \
                and old.link_out is self.link_out \
                and old.error is esm.error and old.drive_alarm is drive_alarm:
            return  # the same inputs (field by field: building LedInputs costs more)
        inputs = LedInputs(esc=self.esc, on_line=on_line, link=self.link,
                           link_out=self.link_out, activity=activity,
                           state=esm.state, error=esm.error, drive_alarm=drive_alarm)
        if inputs != self._led_inputs:
            self._led_inputs = inputs
            self.leds.update(now, wanted_patterns(inputs), self.emit)

    @staticmethod
    def _names(assignment: Assignment) -> str:
        return ", ".join(f"0x{i:04X}" for i in assignment.assigned) or "nothing"

    def _pdo_view(self, pdos: list, assignment: Assignment) -> list[dict[str, Any]]:
        return [{"index": f"0x{p.map_index:04X}", "assigned": p.map_index in assignment.assigned,
                 "mapping": [f"0x{i:04X}:{s:02X}/{b}" for i, s, b in map(split_entry, p.mapped)]}
                for p in pdos]

    def snapshot(self) -> dict[str, Any]:
        esm, inputs = self.esm, self.read_inputs()
        return {
            "kind": self.KIND, "id": self.device_id, "drive": self.drive.device_id,
            "on_line": self.on_line, "link": self.link, "link_out": self.link_out,
            "box_name": self.box_name,
            "station_address": self.station_address,
            "esm": esm.state.label if self.on_line else OFF, "requested": esm.requested.label,
            "al_status": esm.register, "al_status_code": esm.code,
            "al_status_text": describe_al_status_code(esm.code), "error": esm.error.value,
            "slot": self.slot(), "csp": self.csp.active,
            "mode_display": self.csp.mode_display(),
            "rx_assign": [f"0x{i:04X}" for i in self.rx_assign.assigned],
            "tx_assign": [f"0x{i:04X}" for i in self.tx_assign.assigned],
            "rx_pdos": self._pdo_view(self.rx_pdos, self.rx_assign),
            "tx_pdos": self._pdo_view(self.tx_pdos, self.tx_assign),
            "outputs": self.applied.hex(" ").upper() if self.applied is not None else None,
            "inputs": inputs.hex(" ").upper() if inputs is not None else None,
            "process_data_control": self.pd_control, "frames": self.frames,
            "error_register": self.dictionary.peek(0x1001, 0),
            "last_emergency": f"0x{self.emergencies.history.latest & 0xFFFF:04X}"
            if self.emergencies.history.count else None,
            "sdo": list(self.sdo_log),
        }
