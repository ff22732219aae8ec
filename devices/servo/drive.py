"""The servo drive: one state behind the register view (R00..R133, parameters) and the CiA 402
object dictionary, a motor that moves, alarms, digital I/O and the flash.

Seed 004 ch. 1-5, digest §5. docs/servo-drive.md explains the choices made where the seed is
ambiguous. The drive advances in ticks of at most 1 ms of simulated time.
"""

from __future__ import annotations

import logging
import random
from collections.abc import Mapping
from typing import Any

from devices.device import CommandError, DeviceModel
from devices.events import AlarmChanged, LogLine
from devices.flash import FlashStore
from devices.servo import control, ds402
from devices.servo.actions import DriveActions
from devices.servo.alarms import AlarmBank, AlarmSpec, Effect, alarm_table
from devices.servo.config import DriveConfig
from devices.servo.ds402 import Command, State
from devices.servo.errors import AccessError
from devices.servo.io import INPUT_NAMES, LatchFilter
from devices.servo.leds import network_leds
from devices.servo.modes import MODE_CLASSES, Mode
from devices.servo.motion import Trajectory
from devices.servo.od_map import IndirectAccess, build_object_dictionary
from devices.servo.parameters import (
    FIELDBUS_BY_C9,
    PARAMETER_BY_NAME,
    PARAMETERS,
    SAVE_COMMAND_ADDRESS,
    SAVE_COMMAND_VALUE,
    ParameterSpec,
    check_node_number,
    parameter_spec,
)
from devices.servo.plant import Plant
from devices.servo.readings import CurrentMeter, DriveReadings
from devices.servo.registers import (
    DISABLED_32,
    MODE_NAMES,
    REGISTERS,
    R,
    register_spec,
)
from devices.servo.saving import DriveFlash
from devices.servo.statemachine import DriveStateMachine
from devices.servo.stillness import StillSteps, filter_only, may_settle, state_key
from devices.servo.ticking import SWITCHES, DriveTick

__all__ = ["DriveConfig", "ServoDrive"]

logger = logging.getLogger(__name__)

TICK_US = 1_000
_TICK_S = TICK_US / 1e6  # dt_us / 1e6 of a whole tick, as the step loop computes it
BOOT_US = 50_000  # Not ready to switch on -> Switch on disabled after the self test
_FOLLOWING_ERROR_WINDOW = int(R.FOLLOWING_ERROR_WINDOW)  # an enum member's lookup is slow
# A quiet drive stays quiet until something from outside touches it: its quiet span has no end
# of its own. quiet_until says this many steps (about 50 days of 1 ms steps); the rig takes the
# least of every device's answer and of the steps it was asked for.
QUIET_FOREVER_STEPS = 1 << 32


class ServoDrive(DriveTick, DriveStateMachine, DriveFlash, DriveReadings, DriveActions,
                 DeviceModel):
    KIND = "servo"
    SKIP_STILL = True  # False: every step in full (tests/hardening/test_still_steps.py)

    def __init__(self, device_id: str, rng: random.Random, config: DriveConfig,
                 flash: FlashStore) -> None:
        super().__init__(device_id=device_id, rng=rng)
        self.config, self.flash = config, flash
        self.geometry = config.geometry()
        start = config.start_position / config.feed_constant
        self.plant = Plant(self.geometry, start)
        self.trajectory = Trajectory(start)
        self.wired: dict[str, bool] = {"ten": config.ten_wired, "ien": config.ien_wired}
        self.meter = CurrentMeter()
        # L/A, Status, Error on the front: the EtherCAT slave drives them (devices/servo/leds.py)
        self.network_leds = network_leds(device_id)
        self.powered = False
        self.state = State.NOT_READY_TO_SWITCH_ON
        self.params: dict[int, int] = {}
        self.regs: dict[int, int] = {}
        self.latched_at_power_up: dict[str, int] = {}
        self.master_rpm = 0.0
        self.analog_volts = 0.0
        self._t_us = 0
        # Still steps (devices/servo/stillness.py): the length of the last step if it changed
        # nothing, and what it found; _touched = something from outside may have changed.
        self._touched = True
        self._still = StillSteps()
        self._reset_runtime()
        self.indirect = IndirectAccess(self)
        self.od = build_object_dictionary(self)
        self._power_up()

    # ---- power -----------------------------------------------------------------------------
    def _reset_runtime(self) -> None:
        self.cw = 0
        self.ien_cmd = False
        self.cw_source = "register"
        # An alarm reset came with R00's Ten_cmd held: the register view enables again only
        # on a fresh Ten_cmd 0 -> 1 (docs/servo-drive.md "Re-enabling after an alarm")
        self.ten_cmd_held_at_reset = False
        self.alarms = AlarmBank.empty()
        self.latch = LatchFilter()
        self.latched_flag = False
        self.homed = False
        self.ip_set_point = 0
        # 0x60F8 max slippage: stored, not used, and not among the objects a save keeps (ch. 4
        # "Salvataggio su flash"), so it starts from 0 at every power-up (Reset-Application)
        self.max_slippage = 0
        self.saving_until: int | None = None
        self.save_pending: str | None = None
        self.save_trigger: str | None = None
        self.save_done = self.load_done = False
        self._save_blob = b""
        self._fe_ms = 0.0
        self._was_allowed = False
        self._fault_effect = Effect.RELEASE
        self._levels: dict[str, bool] = {}
        # (wiring, switches, levels) of the last tick's levels (ticking.py); a cache
        self._levels_cache: tuple[dict[str, bool], tuple[bool, ...], dict[str, bool]] | None \
            = None
        self.mode_logic: Mode = MODE_CLASSES[1]()

    def _power_up(self) -> None:
        lasting = self.alarms.after_power_cycle()  # a fault in the hardware is still there
        self._reset_runtime()
        self.params, self.regs = self._first_power_up_values()
        bad_flash = self._load_image(self.flash.load(), include_mode=True)
        self.latched_at_power_up = {name: self.params[PARAMETER_BY_NAME[name].address]
                                    for name in ("c7", "c9", "n1", "d8")}
        self.powered = True
        self.boot_until = self._t_us + BOOT_US
        self.theta_zero = self.plant.theta
        self.trajectory.hold(self.plant.theta)
        self.mode_logic = MODE_CLASSES[self.mode]()
        self._levels = self.input_levels()
        self.log(f"power on: c7 = {self.node_id}, c9 = {self.latched_at_power_up['c9']} "
                 f"({self.fieldbus})")
        if bad_flash:
            self.log(f"flash content rejected: {bad_flash}")
            self.raise_alarm(9)
        # The self test finds an injected fault whose cause was not cleared ("la condizione di
        # allarme persiste", ch. 5): in Not ready to switch on, as the rejected image's alarm 9,
        # so the drive comes up in Fault (13, 14) before any master can enable it.
        for code in lasting:
            self.raise_alarm(code, injected=True)

    def _power_down(self) -> None:
        if self.saving:
            self.log("power off during a flash save: the flash keeps its previous content")
        self.mode_logic.halted(self)
        self._set_state(State.NOT_READY_TO_SWITCH_ON, 0)
        # The display and R46 go dark with the drive: every latched alarm ends here in the event
        # log (an injected cause is raised again by the self test at power-up), or a log read
        # later would show it raised for good.
        for code in self.alarms.latched:
            self.emit(AlarmChanged(self.now_us, self.device_id, code=str(code),
                                   name=self.alarm_table[code].name, active=False))
        self.powered = False
        self.saving_until = None
        self.log("power off")

    @property
    def responding(self) -> bool:
        """False while powered off or saving to flash (the drive does not answer, ch. 2)."""
        return self.powered and not self.saving

    @property
    def saving(self) -> bool:
        return self.saving_until is not None

    @property
    def node_id(self) -> int:
        return self.latched_at_power_up["c7"]

    @property
    def fieldbus(self) -> str:
        return FIELDBUS_BY_C9.get(self.latched_at_power_up["c9"], "none")

    @property
    def alarm_table(self) -> dict[int, AlarmSpec]:
        return alarm_table(self.fieldbus)

    # ---- register / parameter view ------------------------------------------------------------
    @property
    def mode(self) -> int:
        return self.regs[R.MODES_OF_OPERATION]

    def reg(self, n: int) -> int:
        return self.regs[n]

    def is_register(self, n: int) -> bool:
        return isinstance(n, int) and n in REGISTERS

    def parameter_addresses(self) -> list[int]:
        return sorted(PARAMETERS)

    def is_parameter(self, address: int) -> bool:
        return address in PARAMETERS or address == SAVE_COMMAND_ADDRESS

    def read_register(self, n: int) -> int:
        register_spec(n)
        live = self.live_register(n)
        return live if live is not None else self.regs[n]

    def write_register(self, n: int, value: int) -> None:
        self._touched = True
        spec = register_spec(n)
        if not spec.writable:
            raise AccessError("readonly", f"R{n:02d} {spec.name} is read-only")
        value = spec.check(value)
        self._require_power()
        if n == R.CONTROL_WORD:
            self._write_control_register(value)
        elif n == R.MODES_OF_OPERATION:
            self.set_mode(value)
        else:
            self.regs[n] = value
            if n == R.TARGET_POSITION and self.mode == 7:
                self.ip_set_point = value

    def read_parameter(self, address: int) -> int:
        if address == SAVE_COMMAND_ADDRESS:
            return 0
        spec = parameter_spec(address)
        live = self.live_parameter(spec.name)
        return live if live is not None else self.params[address]

    def write_parameter(self, address: int, value: int) -> None:
        self._touched = True
        if address == SAVE_COMMAND_ADDRESS:
            self.write_save_command(value)
            return
        spec = parameter_spec(address)
        value = self.check_parameter(spec, value)
        self._require_power()
        self.params[address] = value

    def check_parameter(self, spec: ParameterSpec, value: int) -> int:
        """``value`` if the parameter ``spec`` may be written with it now (every write path:
        Modbus, the indirect 0x2000 / 0x2006 access); c7's range depends on the c9 stored now."""
        if not spec.writable:
            raise AccessError("readonly", f"parameter {spec.name} is read-only")
        value = spec.check(value)
        if spec.name == "c7":
            check_node_number(value, self.params[PARAMETER_BY_NAME["c9"].address])
        return value

    def write_save_command(self, value: int) -> None:
        """0x3802 = 0x0011 (FC 06, or FC 16 as the 32-bit 0x00000011): save to flash."""
        if value != SAVE_COMMAND_VALUE:
            raise AccessError("value", f"0x{SAVE_COMMAND_ADDRESS:04X} takes only "
                                       f"0x{SAVE_COMMAND_VALUE:04X} (save to flash)")
        self._require_power()
        self.request_save("0x3802 = 0x0011")

    def _require_power(self) -> None:
        if not self.powered:
            raise CommandError(f"servo '{self.device_id}' is powered off")

    def input_level(self, name: str) -> bool:
        """The level at the input: the wiring (set_input), or the carriage on a switch."""
        if name in SWITCHES:
            return self.input_levels()[name]
        return self.wired.get(name, False)

    def input_levels(self) -> dict[str, bool]:
        return self.levels_at(self.geometry.switches(self.plant.theta))

    def levels_at(self, switches: tuple[bool, bool, bool]) -> dict[str, bool]:
        """The input levels with the switches (neg, pos, home) as the carriage actuates them."""
        wired = self.wired
        levels = {name: wired.get(name, False) for name in INPUT_NAMES}
        for name, actuated in zip(SWITCHES, switches, strict=True):
            levels[name] = levels[name] or actuated
        return levels

    @property
    def motion_enabled(self) -> bool:
        """Ien_st: in operation, with the Ien_cmd command and the IEN consent, not saving (a
        save started with IEN low holds the axis until it is over: saving.may_save)."""
        return self.state is State.OPERATION_ENABLED and self.ien_cmd \
            and self.input_level("ien") and self.input_level("ten") \
            and self.saving_until is None

    def motion_blocked(self) -> str | None:
        """Why a motion command would not move the axis now, in the operator's words; None
        when it would. The command is still taken (a master's writes are), this only says
        why nothing happens, for the panel's notice."""
        label = self.state.label
        if self.state in (State.FAULT, State.FAULT_REACTION_ACTIVE):
            return (f"not enabled ({label}, alarm {self.alarms.active}) - reset the alarm, "
                    "then enable torque")
        if self.released_by_reset:
            return ("not enabled (Switch on disabled after the alarm reset, Ten_cmd held) - "
                    "enable torque again: R00 = 0, then 3")
        if not self.input_level("ten"):
            # the consent, not the command: a held Ten_cmd / 0x000F takes 4 when TEN is back
            if self.state is State.SWITCHED_ON \
                    and ds402.decode(self.cw) is Command.ENABLE_OPERATION:
                return ("no torque (TEN input low) - switch TEN on: the enable is held, "
                        "torque comes back with it")
            return f"not enabled ({label}, TEN input low) - switch TEN on and enable torque"
        if self.state is not State.OPERATION_ENABLED:
            return f"not enabled ({label}) - enable torque first"
        if not self.input_level("ien"):
            return "motion not enabled (IEN input low) - switch IEN on: motion resumes with it"
        if not self.ien_cmd:
            return "motion not enabled (Ien_cmd off, R00 bit 1) - Enable sets it"
        if self.cw & ds402.CW_HALT:
            # The panel's Enable (R00 = 3) and Move write a control word without it
            stopped = control.HALT_HINT.get(self.fieldbus, control.HALT_HINT_ANY)
            return f"{stopped} - Enable or Move clears it"
        return None

    @property
    def released_by_reset(self) -> bool:
        """An alarm reset found R00's Ten_cmd held and left the axis released: only a fresh
        Ten_cmd 0 -> 1 enables (docs/servo-drive.md "Re-enabling after an alarm")."""
        return self.ten_cmd_held_at_reset and self.state is State.SWITCH_ON_DISABLED

    @property
    def motion_allowed(self) -> bool:
        return self.motion_enabled and not self.cw & ds402.CW_HALT

    @property
    def following_error_exceeded(self) -> bool:
        window = self.regs[_FOLLOWING_ERROR_WINDOW]
        return window != DISABLED_32 and abs(self.following_error_user) > window

    @property
    def following_error_below_window(self) -> bool:
        """End of Job's condition, ch. 2: the error "inferiore a quello specificato nella
        relativa finestra", strictly below R03 (an error equal to it is neither this nor
        alarm 16's "superato"); R03 = 0xFFFFFFFF is no check (ch. 4, 0x6065), so always."""
        window = self.regs[_FOLLOWING_ERROR_WINDOW]
        return window == DISABLED_32 or abs(self.following_error_user) < window

    def log(self, text: str) -> None:
        self.emit(LogLine(self.now_us, self.device_id, text=text))

    def set_ip_set_point(self, value: int) -> None:
        """0x60C1:1, user units: taken at the next interpolation period (or Sync)."""
        self._touched = True
        self._require_power()
        self.ip_set_point = value

    def set_ip_set_point_16(self, value: int) -> None:
        """0x2002: the low 16 bits; the set-point moves to the nearest value with those bits."""
        self._touched = True
        self._require_power()
        delta = (value - self.ip_set_point) & 0xFFFF
        self.ip_set_point += delta - 0x10000 if delta >= 0x8000 else delta

    def velocity_sensor(self) -> int:
        """0x6069: increments/s of an 8192-pulse sensor; with 0x6040 bit 12, the master's speed
        in increments/ms (ch. 4)."""
        if self.cw & ds402.CW_MASTER_SPEED:
            value = self.master_speed_incr_ms
        else:
            value = self.plant.omega * 8192.0
        return int(max(-0x8000_0000, min(0x7FFF_FFFF, round(value))))

    def set_mode(self, mode: int) -> None:
        self._touched = True
        if mode not in MODE_NAMES:
            raise AccessError("value", f"mode {mode} is not one of "
                                       f"{', '.join(str(m) for m in MODE_NAMES)}")
        self._require_power()
        if mode == self.mode:
            return
        self.mode_logic.halted(self)
        self.regs[R.MODES_OF_OPERATION] = mode
        # R00 bits 5-7 mean what the selected mode says (ch. 1 "specifico del modo
        # selezionato"): the other view is read again in the new mode, with no edge. A
        # register master's R00 = 0x43 after homing is Pos_str 0 in mode 1, so 0x23 starts;
        # a CiA 402 master's 0x6040 stays as written (DSP 402) and R00 shows it in the new mode.
        if self.cw_source == "register":
            self.cw = control.controlword_from_register(self.regs[R.CONTROL_WORD], mode)
        else:
            self.regs[R.CONTROL_WORD] = control.register_from_controlword(self.cw, mode,
                                                                          self.ien_cmd)
        self.mode_logic = MODE_CLASSES[mode]()
        self.mode_logic.enter(self)
        self._was_allowed = False
        self.log(f"mode {mode} ({MODE_NAMES[mode]})")

    # ---- time -------------------------------------------------------------------------------
    def touch(self) -> None:
        """Something from outside changed the drive: the next step runs in full."""
        self._touched = True

    def apply(self, action: str, args: Mapping[str, Any], module: int | None = None) -> Any:
        self._touched = True
        return super().apply(action, args, module)

    def step(self, now_us: int) -> None:
        t_us = self._t_us  # only this method writes _t_us
        if now_us < t_us:
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {t_us})")
        span, alarms, still = now_us - t_us, self.alarms, self._still
        if span == still.dt and not self._touched and alarms is still.alarms \
                and alarms.changes == still.changes and self.SKIP_STILL:
            self._t_us = self.now_us = now_us  # a repeat of a step that changed nothing
            return
        if self._touched:
            self._touched = False
            self._cruise = None  # what a steady tick recorded may have changed (ticking.py)
            still.restart()
            still.filter_dt = None
        elif alarms is not still.alarms or alarms.changes != still.changes:
            self._cruise = None
            still.filter_dt = None  # the alarm bank changed from outside
        elif span != still.filter_dt:
            still.filter_dt = None  # another step length
        # plant.omega first: may_settle's first test, without the call for a moving drive
        before = state_key(self) if span and self.plant.omega == 0.0 and may_settle(self) \
            and still.due() else None
        if before is None and span == TICK_US:
            # one tick and no still check (a moving drive's step): the loop and the
            # bookkeeping below, written out for that case
            self._t_us = self.now_us = now_us
            self._tick(_TICK_S)
            still.dt = None
            still.alarms, still.changes = self.alarms, self.alarms.changes
            return
        queued = len(self.events.items) if before is not None else 0
        while t_us < now_us:
            dt_us = now_us - t_us
            if dt_us > TICK_US:  # min(TICK_US, now_us - t_us)
                dt_us = TICK_US
            t_us += dt_us
            self._t_us = self.now_us = t_us
            self._tick(dt_us / 1e6)
        self.now_us = now_us
        settled = False
        if before is not None:
            quiet = not self._touched and len(self.events.items) == queued and may_settle(self)
            after = state_key(self) if quiet else None
            settled = after == before
            still.checked(settled)
            # changed nothing but the current meter's filter: quiet spans (quiet_until)
            still.filter_dt = span if after is not None and filter_only(before, after) \
                else None
        still.dt = span if settled else None
        still.alarms, still.changes = self.alarms, self.alarms.changes

    # ---- quiet spans (docs/servo-drive.md "Quiet spans") --------------------------------------
    def quiet_until(self, step_us: int) -> int:
        """Unbounded (:data:`QUIET_FOREVER_STEPS`) while the drive's steps of ``step_us`` are
        proven to change nothing but the current meter's filter; else ``now_us``.

        The proof is the still step's (stillness.py): the last checked step, of this length,
        emitted nothing, left every part of the state but the meter as it found it and read no
        clock (:func:`may_settle`: no boot, save, indirect access or latch timing under way);
        nothing in a step reads the meter but the meter itself, so every later step of that
        length does the same until something from outside touches the drive (a command, a
        write, an alarm: ``_touched``, the alarm bank's change count). Nothing else in a
        standing drive's step depends on time: no rng draw, no blinking (the display is a
        function of the state), no timer counting (a counting timer, e.g. mode 3's speed
        window, changes the state: no proof) — but for zero speed in the velocity modes, kept
        as a start time and read off the clock: the span ends before it comes on. Relies on
        the rig's promise that no other model touches the drive in the span (its CANopen node
        and CoE slave are quiet too, so they write nothing to it and raise no alarm on it).
        """
        still, alarms, now = self._still, self.alarms, self.now_us
        if self._touched or step_us != still.filter_dt or alarms is not still.alarms \
                or alarms.changes != still.changes or not self.SKIP_STILL:
            return now
        monitor = self.mode_logic.monitor
        if monitor is not None and self.powered:
            # Zero speed comes on by the clock (modes.SpeedMonitor): the status word changes
            # with no step changing anything, and the node / slave read it every step.
            at = monitor.zero_speed_at(self)
            if at is not None and at > now:
                return now + (at - 1 - now) // step_us * step_us
        return now + QUIET_FOREVER_STEPS * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        """As the quiet steps up to ``t_us``: only the clock and the current meter's filter
        move (:meth:`CurrentMeter.repeat`, the same arithmetic tick by tick)."""
        now_us = self.now_us
        if t_us == now_us:
            return
        span = self._still.filter_dt
        if span is None or span != step_us or (t_us - now_us) % span or t_us < now_us \
                or now_us != self._t_us:
            raise ValueError(f"{self.device_id}: no quiet span to {t_us} us")
        if self._still.dt is None:  # the filter still settles (else it rests: nothing to do)
            ticks = [TICK_US] * (span // TICK_US) + ([span % TICK_US] if span % TICK_US else [])
            self.meter.repeat(tuple(dt_us / 1e6 for dt_us in ticks), (t_us - now_us) // span)
        self._t_us = self.now_us = t_us

    def snapshot(self) -> dict[str, Any]:
        return self.build_snapshot()
