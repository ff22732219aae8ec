"""What the drive measures and reports: positions in user units, live registers, currents and
the snapshot the dashboard draws from."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from devices.servo import control, ds402
from devices.servo.display import display_text
from devices.servo.ds402 import State
from devices.servo.homing import limits_used
from devices.servo.io import INPUT_NAMES, input_word, output_levels
from devices.servo.modbus_map import E3_ADDRESS, active_map
from devices.servo.motion import Limits, Shape
from devices.servo.registers import MODE_NAMES, R

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

S32_MAX = 0x7FFF_FFFF
S16_MAX = 0x7FFF
RMS_TIME_CONSTANT_S = 1.0
JAM_CURRENT = 200.0  # % of nominal the motor draws pushing a jammed load
_K_1MS = 1.0 - math.exp(-0.001 / RMS_TIME_CONSTANT_S)  # CurrentMeter.update's k at 1 ms
_sqrt = math.sqrt
_IN_TORQUE = ds402._IN_TORQUE_ORDERED  # State.in_torque without the property call
_FEED_CONSTANT = int(R.FEED_CONSTANT)  # an enum member's lookup costs more than the dict's


def _clamp(value: float, limit: int) -> int:
    return int(max(-limit - 1, min(limit, round(value))))


class CurrentMeter:
    """o1 instantaneous current, o2 RMS current, o3 overload (% of I2T), all in % of nominal."""

    # Slots: read every tick of a moving drive, and a __dict__ read once (a stillness key)
    # would slow each access for good on CPython 3.11 (devices/stillness.py slot_names).
    __slots__ = ("_mean_square", "instant", "overload", "rms")

    def __init__(self) -> None:
        self.instant = self.rms = self.overload = 0.0
        self._mean_square = 0.0

    def update(self, d: ServoDrive, accel: float, dt: float) -> None:
        # min(x, cap) written out as "cap if cap < x else x", its exact meaning (every tick)
        if d.state in _IN_TORQUE:
            config, plant = d.config, d.plant
            inertia = 1.0 + config.load_inertia
            torque = 5.0 + 50.0 * abs(accel) / config.quick_stop_decel * inertia
            if plant.jammed or plant.blocked:
                torque += JAM_CURRENT * min(abs(d.following_error_user) / d.feed, 1.0)
            cap = 3.0 * d.params[5]  # d5 caps the current
            self.instant = instant = cap if cap < torque else torque
        else:
            self.instant = instant = 0.0
        # the filter constant of a 1 ms tick is a constant (dt == 0.001: the same bits)
        k = _K_1MS if dt == 0.001 else 1.0 - math.exp(-dt / RMS_TIME_CONSTANT_S)
        mean_square = self._mean_square
        self._mean_square = mean_square = mean_square + (instant ** 2 - mean_square) * k
        self.rms = rms = _sqrt(mean_square)
        overload = 100.0 * (rms / 100.0) ** 2
        self.overload = 999.0 if overload > 999.0 else overload

    def repeat(self, dts: tuple[float, ...], steps: int) -> None:
        """As ``steps`` steps of ticks ``dts`` (seconds each) would move the meter with the
        instant current as it is (a standing drive whose steps change nothing else: quiet
        spans, drive.py). The filter's own arithmetic, value for value: the same expressions
        in the same order, so the same bits. Stops early once a whole step leaves the mean
        square as it was (a fixed point: every further step does the same)."""
        if steps <= 0:
            return
        ks = tuple(_K_1MS if dt == 0.001 else 1.0 - math.exp(-dt / RMS_TIME_CONSTANT_S)
                   for dt in dts)
        square = self.instant ** 2
        mean_square = self._mean_square
        for _ in range(steps):
            start = mean_square
            for k in ks:
                mean_square = mean_square + (square - mean_square) * k
            if mean_square == start:
                break
        self._mean_square = mean_square
        self.rms = rms = _sqrt(mean_square)
        overload = 100.0 * (rms / 100.0) ** 2
        self.overload = 999.0 if overload > 999.0 else overload


class DriveReadings:
    """Mixin of :class:`~devices.servo.drive.ServoDrive`: measured values and the snapshot."""

    @property
    def position_user(self: ServoDrive) -> int:
        """position_actual_value (R06 / 0x6064)."""
        return _clamp((self.plant.theta - self.theta_zero) * self.feed, S32_MAX)

    @property
    def velocity_user(self: ServoDrive) -> float:
        return self.plant.omega * self.feed

    @property
    def following_error_user(self: ServoDrive) -> float:
        return (self.trajectory.position - self.plant.theta) * self.feed

    @property
    def position_lag_s(self: ServoDrive) -> float:
        """The position loop's time constant: i1 = 50 % gives the configured lag."""
        return self.config.position_lag_ms / 1e3 * 50.0 / self.params[35]

    @property
    def master_speed_incr_ms(self: ServoDrive) -> float:
        return self.master_rpm / 60.0 * self.regs[R.MASTER_ENCODER_INCREMENTS] / 1e3

    # ---- units and limits the modes use -------------------------------------------------------
    @property
    def feed(self: ServoDrive) -> int:
        feed = self.regs[_FEED_CONSTANT]
        return feed if feed >= 1 else 1  # max(feed, 1): a feed of 0 counts as 1 unit per turn

    def user_to_rev(self: ServoDrive, position: float) -> float:
        return self.theta_zero + position / self.feed

    def speed_to_rev(self: ServoDrive, speed: float) -> float:
        return speed / self.feed

    def accel_to_rev(self: ServoDrive, accel: float) -> float:
        """Accelerations are user units / s / ms (seed 004 ch. 4, 0x6092)."""
        return accel * 1e3 / self.feed

    @property
    def motor_vmax_rev(self: ServoDrive) -> float:
        """d3 % of the motor's rated speed, in rev/s."""
        return self.config.max_speed_rpm * self.params[3] / 100.0 / 60.0

    def limits(self: ServoDrive, vmax: float | None = None) -> Limits:
        if vmax is None:
            vmax = min(self.speed_to_rev(self.regs[R.PROFILE_VELOCITY]), self.motor_vmax_rev)
        return Limits(vmax, self.accel_to_rev(self.regs[R.PROFILE_ACCELERATION]),
                      self.accel_to_rev(self.regs[R.PROFILE_DECELERATION]),
                      Shape(self.regs[R.MOTION_PROFILE_TYPE]),
                      self.regs[R.ACCELERATION_JERK] / 100.0,
                      self.regs[R.DECELERATION_JERK] / 100.0)

    def quick_stop_limits(self: ServoDrive) -> Limits:
        decel = self.config.quick_stop_decel * self.params[13] / 50.0  # f3, emergency ramp
        return Limits(self.motor_vmax_rev, decel, decel)

    def set_home(self: ServoDrive, home: float) -> None:
        """The home point reads -home_offset (ch. 4: offset -1000 -> position 1000)."""
        self._touched = True  # the next step runs in full (stillness.py)
        self.theta_zero = home + self.regs[R.HOME_OFFSET] / self.feed

    def live_register(self: ServoDrive, n: int) -> int | None:
        if n == R.STATUS_WORD:
            return self.status_register
        if n == R.POSITION_ACTUAL_VALUE:
            return self.position_user
        if n == R.VELOCITY_ACTUAL_VALUE:
            return _clamp(self.velocity_user, S32_MAX)
        if n == R.VELOCITY_MASTER_SENSOR:
            return _clamp(self.master_speed_incr_ms, S16_MAX)
        if n == R.ALARM_CODE:
            return self.alarms.active
        if n == R.DIGITAL_INPUTS:
            return self.input_register
        if n == R.SPEED_RPM:
            return _clamp(self.plant.omega * 60.0, S32_MAX)
        return None

    def live_parameter(self: ServoDrive, name: str) -> int | None:
        meter = self.meter
        values = {"o1": meter.instant, "o2": meter.rms, "o3": meter.overload}
        return round(values[name]) if name in values else None

    def error_code(self: ServoDrive) -> int:
        """0x603F: the error code of the alarm in R46, 0 without alarm (ch. 5 table)."""
        code = self.alarms.active
        return self.alarm_table[code].error_code_or_generic if code else 0

    # ---- status words, outputs, snapshot ------------------------------------------------------
    def status_flags(self: ServoDrive,
                     levels: dict[str, bool] | None = None) -> control.StatusFlags:
        """``levels``: :meth:`input_levels` of now, if the caller has them already."""
        if levels is None:
            levels = self.input_levels()
        mode_flags = self.mode_logic.flags(self) if self.powered else {}
        # 0x6041 bit 15 names the consents, not the state (ch. 4 "segnale TEN basso ... segnale
        # IEN basso"; Ien_cmd is R00's motion enable, held by a CiA 402 master): ch. 5's Ready
        # to switch on reads 0x0621, ch. 6's fresh drive (R00 = 0) 0x8640
        consents = self.ien_cmd and levels["ten"] and levels["ien"]
        stopping = self.state in (State.QUICK_STOP_ACTIVE, State.FAULT_REACTION_ACTIVE) or (
            self.state is State.OPERATION_ENABLED and not self.motion_allowed
            and not self.trajectory.idle)
        return control.StatusFlags(
            state=self.state, mode=self.mode, motion_enabled=self.motion_enabled,
            stopping=stopping, latched=self.latched_flag, latch_input=levels["latch"],
            target_reached=self.powered and self.mode_logic.target_reached(self),
            limit_active=any(levels[name] for name in limits_used(self.reg(R.HOMING_METHOD))),
            save_done=self.save_done, load_done=self.load_done,
            velocity_forced_zero=not consents, **mode_flags)

    @property
    def status_register(self: ServoDrive) -> int:
        return control.register_status(self.status_flags())

    @property
    def statusword(self: ServoDrive) -> int:
        return control.cia402_status(self.status_flags())

    def outputs(self: ServoDrive) -> dict[str, bool]:
        if not self.powered:
            return dict.fromkeys(("end_of_job", "out1", "brake", "near_target"), False)
        primary = {"end_of_job": self.mode_logic.end_of_job(self),
                   "near_target": self.mode_logic.near_target(self),
                   "brake": self.state.in_torque}  # 24 V releases the brake
        return output_levels(primary, self.regs[R.DIGITAL_OUT_MASK], self.regs[R.DIGITAL_OUTPUTS])

    @property
    def display(self: ServoDrive) -> str:
        return display_text(self.powered, self.saving, self.alarms.active, self.state.in_torque)

    @property
    def input_register(self: ServoDrive) -> int:
        return input_word(self.input_levels())

    def build_snapshot(self: ServoDrive) -> dict[str, Any]:
        levels = self.input_levels()
        flags = self.status_flags(levels)  # once for both words (status_register, statusword)
        r05, sw = control.register_status(flags), control.cia402_status(flags)
        code = self.alarms.active
        alarm = self.alarm_table[code].as_dict() if code else None
        f = self.config.feed_constant
        return {
            "kind": "servo", "id": self.device_id, "powered": self.powered,
            "responding": self.responding, "fieldbus": self.fieldbus, "node_id": self.node_id,
            # the Modbus address map e3 selects, read at every request (ch. 2): the panel's
            # address hints follow it
            "modbus_map": active_map(self.params.get(E3_ADDRESS, 0)),
            "ds402_state": self.state.label, "controlword": self.cw, "statusword": sw,
            # the panel's next step: R00 still reads Ten_cmd, yet only a fresh one enables
            "released_by_reset": self.released_by_reset,
            "control_register": self.regs[R.CONTROL_WORD], "status_register": r05,
            "status_bits": {name: bool(r05 >> bit & 1)
                            for bit, name in control.status_bit_names(self.mode).items()},
            "statusword_bits": {name: bool(sw >> bit & 1)
                                for bit, name in ds402.STATUSWORD_BITS.items()},
            "mode": self.mode, "mode_name": MODE_NAMES[self.mode],
            "position": (self.plant.theta - self.theta_zero) * self.feed,
            "position_counts": self.position_user,
            "velocity": self.velocity_user, "following_error": self.following_error_user,
            "target": self.regs[R.TARGET_POSITION],
            "target_velocity": self.regs[R.TARGET_VELOCITY],
            "ten": levels["ten"], "ien": levels["ien"],
            "inputs": {name: levels[name] for name in INPUT_NAMES},
            "outputs": self.outputs(), "alarm": alarm, "alarms": list(self.alarms.latched),
            # the instructor's: what inject_alarm left until clear_alarm (docs/classroom.md)
            "injected": [{"code": c, "name": self.alarm_table[c].name}
                         for c in self.alarms.injected_causes()],
            "error_code": self.error_code(), "display": self.display, "saving": self.saving,
            "save_pending": self.save_pending is not None, "homed": self.homed,
            "jammed": self.plant.jammed,
            "limits": {"neg": levels["neg_limit"], "pos": levels["pos_limit"],
                       "home": levels["home"]},
            "axis": {"neg_limit": self.config.neg_limit, "pos_limit": self.config.pos_limit,
                     "home_switch": self.config.home_switch,
                     "carriage": self.plant.theta * f, "motor_turns": self.plant.theta},
            "current": {"o1": round(self.meter.instant), "o2": round(self.meter.rms),
                        "o3": round(self.meter.overload)},
            "leds": self.network_leds.snapshot(),
            # the speed mode 3 runs to: R13, or R30 with Select high (ch. 2 "Select"); only
            # in mode 3, the one mode whose set-point is a register
            **({"speed_set_point": self.mode_logic.target_user(self)}
               if self.mode in control.SPEED_SET_POINT else {}),
        }
