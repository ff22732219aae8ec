"""One tick of the drive (at most 1 ms): state machine, motion, current, inputs and checks.

Seed 004 ch. 1-5 through the modules this one calls; docs/servo-drive.md §Step cost. This is
the hot path of a moving drive (docs/performance.md, benchmark 1 "in motion"), so it is
written for speed without changing a result: the same work in the same order with the same
floating-point expressions as the plain code, minus what cannot change anything:

- parts whose inputs say they do nothing are not called (the indirect access with no job, the
  flash save with none pending or running, the latch filter with its input low and nothing
  captured, the switch and marker crossings when the mode does not watch them: only homing);
- the input levels dict is rebuilt only when the wiring or a switch changed (the same dict
  object otherwise: nobody mutates it);
- hot constants (enum members, register numbers) are module names, because reading an enum
  member off its class costs a Python-level lookup; states are compared by identity;
- the helpers a tick called every time (the motion, the limit and following-error checks,
  ``feed``, ``following_error_user``, ``trajectory.idle``, ``geometry.switches``,
  ``motion_allowed``, ``_evaluate``'s "nothing new" test) are written out here, each the same
  expression as the helper's: a Python call costs more than most of these bodies
  (docs/servo-drive.md §Step cost in motion);
- the position loop's lag is kept with the i1 it was computed for (``_lag_cache``): the config
  is frozen, so the lag changes only with i1, however i1 is written (parameter, flash load).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

from devices.servo import ds402
from devices.servo.ds402 import Command, State
from devices.servo.homing import limits_used as _limits_used
from devices.servo.mode_base import Changes, Mode
from devices.servo.modes import Velocity as _VELOCITY
from devices.servo.plant import STOPPED_REV_S as _STOPPED_REV_S
from devices.servo.plant import follow_demand
from devices.servo.readings import _K_1MS, _sqrt
from devices.servo.registers import DISABLED_32, R

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive
    from devices.servo.motion import Ramp, Trajectory
    from devices.servo.plant import Plant

SWITCHES = ("neg_limit", "pos_limit", "home")
S32_MAX = 0x7FFF_FFFF
_NOT_READY = State.NOT_READY_TO_SWITCH_ON
_ENABLED, _QUICK_STOP = State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE
_FAULT_REACTION = State.FAULT_REACTION_ACTIVE
_IN_TORQUE = (_ENABLED, _QUICK_STOP, _FAULT_REACTION)  # State.in_torque, by identity
_LATCHED_POSITION = int(R.LATCHED_POSITION)
_FOLLOWING_ERROR_WINDOW = int(R.FOLLOWING_ERROR_WINDOW)
_FOLLOWING_ERROR_TIMEOUT = int(R.FOLLOWING_ERROR_TIMEOUT)
_FEED_CONSTANT = int(R.FEED_CONSTANT)
_VELOCITY_THRESHOLD = int(R.VELOCITY_THRESHOLD)
_VELOCITY_WINDOW = int(R.VELOCITY_WINDOW)
_TARGET_VELOCITY = int(R.TARGET_VELOCITY)
_AUX_IN_1 = int(R.AUX_IN_1)
_HOMING_METHOD = int(R.HOMING_METHOD)
_IN_TORQUE_ORDERED = ds402._IN_TORQUE_ORDERED  # CurrentMeter.update's test
_I1 = 35  # parameter i1, the position loop gain (position_lag_s)
_CW_HALT = ds402.CW_HALT
_NO_OBSERVER = Mode.observe
_NEVER_BUSY = Mode.busy  # the property of every mode but homing: always False


class DriveTick:
    """Mixin of :class:`~devices.servo.drive.ServoDrive`: ``_tick`` and what it calls."""

    # (i1, position_lag_s at that i1): the lag is a function of i1 alone (the config is frozen)
    _lag_cache: tuple[int, float] | None = None
    # A steady jog's tick recorded by the full tick (_cruise_tick): (dt, lag, vmax, feed,
    # speed threshold, speed window, speed monitor, target, levels cache, following-error
    # window or None, its timeout, theta_zero); None: no record. ServoDrive.step drops it
    # when anything from outside touched the drive or the alarm bank moved.
    _cruise: tuple[Any, ...] | None = None
    # False: every tick runs in full (tests/devices/servo/test_servo_cruise.py compares).
    FAST_CRUISE: ClassVar[bool] = True

    def _tick(self: ServoDrive, dt: float) -> None:
        cruise = self._cruise
        if cruise is not None and cruise[0] == dt:
            trajectory = self.trajectory
            plan, index = trajectory._plan, trajectory._index
            if index < len(plan):
                segment = plan[index]
                if segment.v0 == segment.v1 and dt < segment.duration - trajectory._elapsed \
                        and not self.indirect._jobs:
                    self._cruise_tick(dt, cruise, trajectory, segment)
                    return
        self._cruise = None
        changes = self.alarms.changes
        i1, cached_lag = self.params[_I1], self._lag_cache
        if cached_lag is not None and cached_lag[0] == i1:
            lag = cached_lag[1]
        else:
            lag = self.position_lag_s
            self._lag_cache = (i1, lag)
        plant, trajectory = self.plant, self.trajectory
        if not self.powered:
            plant.step(dt, None, lag)
            trajectory.hold(plant.theta, plant.omega)
            return
        t_us = self._t_us
        if self.state is _NOT_READY and t_us >= self.boot_until:
            self._transition(Command.SELF_TEST_DONE)
        if self.indirect._jobs:  # without a job its step changes nothing
            self.indirect.step(t_us)
        if self.save_pending or self.saving_until is not None:  # else nothing to update
            self._update_saving()
        wired = self.wired
        if (self.state, self.cw, self.cw_source, wired.get("ten", False)) \
                != self._quiet_evaluation:  # else _evaluate returns at once
            self._evaluate()
        monitor = self.mode_logic.monitor
        if monitor is not None:
            # velocity modes: zero speed follows the axis in every state, not only while the
            # mode runs (R05 bit 7 "asse fermo"); SpeedMonitor.follow_speed, inline, at the
            # tick's start as the mode's step reads the speed
            regs = self.regs
            feed = regs[_FEED_CONSTANT]
            if abs(plant.omega * (feed if feed >= 1 else 1)) <= regs[_VELOCITY_THRESHOLD]:
                if monitor.below_threshold_since_us is None:
                    monitor.below_threshold_since_us = t_us - round(dt * 1e6)
            else:
                monitor.below_threshold_since_us = None
        theta_before, velocity_before = plant.theta, trajectory.velocity
        steady = False  # the steady jog's path, which a cruise record repeats (_cruise_tick)
        # ---- the motion (the demand from the mode, the trajectory, the motor) ----
        state = self.state
        if state not in _IN_TORQUE:
            if self._was_allowed:
                self.mode_logic.halted(self)
                self._was_allowed = False
            plant.step(dt, None, lag)
            trajectory.hold(plant.theta, plant.omega)
        else:
            if state is _ENABLED:
                # motion_allowed, with the state known to be enabled
                allowed = self.ien_cmd and wired.get("ien", False) \
                    and wired.get("ten", False) and not self.cw & _CW_HALT \
                    and self.saving_until is None
                if allowed:
                    mode = self.mode_logic
                    if type(mode) is _VELOCITY:
                        # Velocity.step and target_user, inline (mode 3: every tick of a
                        # jog); a new target plans a new run: the method does that
                        regs = self.regs
                        target = regs[_AUX_IN_1] if wired.get("select", False) \
                            else regs[_TARGET_VELOCITY]
                        if target != mode.commanded:
                            mode.step(self, dt)
                        else:  # the speed window timer, as Velocity.step runs it
                            steady = monitor is mode.monitor and monitor is not None
                            monitor = mode.monitor
                            feed = regs[_FEED_CONSTANT]
                            actual = plant.omega * (feed if feed >= 1 else 1)
                            monitor.in_window_ms = monitor.in_window_ms + dt * 1e3 \
                                if abs(target - actual) <= regs[_VELOCITY_WINDOW] else 0.0
                    else:
                        mode.step(self, dt)
                elif self._was_allowed:
                    self.mode_logic.halted(self)
                    halting = self.motion_enabled  # halt bit: profile deceleration
                    trajectory.stop(self.limits() if halting else self.quick_stop_limits())
                self._was_allowed = allowed
            # Trajectory.advance inline for the step inside a cruise (a jog's usual tick):
            # the same expressions as its first case; anything else takes the method
            plan, index = trajectory._plan, trajectory._index
            segment = plan[index] if index < len(plan) else None
            if segment is not None and dt > 0.0 and segment.v0 == segment.v1 \
                    and dt < segment.duration - trajectory._elapsed:
                trajectory._elapsed = elapsed = trajectory._elapsed + dt
                trajectory.velocity = v0 = segment.v0
                trajectory.position = trajectory._segment_start + v0 * elapsed
            else:
                steady = False
                trajectory.advance(dt)
            demand = trajectory.position
            # motor_vmax_rev's expression: d3 % of the rated speed, rev/s
            vmax = self.config.max_speed_rpm * self.params[3] / 100.0 / 60.0
            if plant.jammed:
                steady = False
                plant.step(dt, demand, lag, vmax)
            else:
                follow_demand(plant, demand, lag, vmax, dt)
            # A quick stop or fault reaction ends at standstill (DSP 402 v1.1, seed 004 ch. 4;
            # F3 "Rampa di emergenza"): the demand at rest (trajectory.idle, inline) and the
            # motor, which lags it, stopped too (plant.standstill, inline) - else the torque
            # went off with the motor still turning and the axis coasted.
            if trajectory._index >= len(trajectory._plan) and trajectory.velocity == 0.0 \
                    and -_STOPPED_REV_S < plant.omega < _STOPPED_REV_S:
                steady = False
                if self.state is _QUICK_STOP:
                    self._transition(Command.STANDSTILL)
                elif self.state is _FAULT_REACTION:
                    self._transition(Command.FAULT_REACTION_DONE)
        # ---- what the motion changed: current, inputs, alarms ----
        accel = (trajectory.velocity - velocity_before) / dt
        if dt == 0.001 and self.state in _IN_TORQUE_ORDERED \
                and not (plant.jammed or plant.blocked):
            _meter_1ms(self, accel)
        else:
            self.meter.update(self, accel, dt)
        quiet_inputs = self._inputs_tick(wired, theta_before, plant.theta)
        # _check_following_error, inline: alarm 16 when |error| > R03 for longer than R04 ms
        regs = self.regs
        window, feed = regs[_FOLLOWING_ERROR_WINDOW], regs[_FEED_CONSTANT]
        if self.state is _ENABLED and window != DISABLED_32 and abs(  # following_error_user
                (trajectory.position - plant.theta) * (feed if feed >= 1 else 1)) > window:
            self._fe_ms += dt * 1e3
            if self._fe_ms > regs[_FOLLOWING_ERROR_TIMEOUT]:
                self._fe_ms = 0.0
                self.raise_alarm(16)
        else:
            self._fe_ms = 0.0
        feed = self.regs[_FEED_CONSTANT]  # again: alarm 16 may have changed what it reads
        if abs((plant.theta - self.theta_zero) * (feed if feed >= 1 else 1)) > S32_MAX:
            self.raise_alarm(15)  # the position no longer fits R06 (S32)
        if steady and quiet_inputs and self.state is _ENABLED and not self._touched \
                and self.FAST_CRUISE \
                and self.alarms.changes == changes and self._was_allowed \
                and not self.indirect._jobs and not self.save_pending \
                and self.saving_until is None:
            # The steady jog's tick, nothing from outside since it began (a write, a command,
            # an alarm, a transition: each sets _touched or moves the alarm bank, and
            # ServoDrive.step drops the record then): its inputs hold for the next ticks.
            # The registers as floats: each is a 32-bit int, which CPython converts exactly
            # when it meets a float (the same bits, the same comparisons), and float-float
            # arithmetic is the interpreter's fast path.
            regs = self.regs
            feed = regs[_FEED_CONSTANT]
            target = regs[_AUX_IN_1] if wired.get("select", False) else regs[_TARGET_VELOCITY]
            window = regs[_FOLLOWING_ERROR_WINDOW]
            self._cruise = (dt, lag, vmax, float(feed if feed >= 1 else 1),
                            float(regs[_VELOCITY_THRESHOLD]), float(regs[_VELOCITY_WINDOW]),
                            monitor, float(target), self._levels_cache,
                            None if window == DISABLED_32 else float(window),
                            float(regs[_FOLLOWING_ERROR_TIMEOUT]), self.theta_zero)

    def _cruise_tick(self: ServoDrive, dt: float, cruise: tuple[Any, ...],
                     trajectory: Trajectory, segment: Ramp) -> None:
        """The steady jog's tick: a velocity mode cruising at its commanded speed, enabled,
        the motor free, no input moving. The full tick recorded its inputs in ``_cruise``;
        with nothing from outside since, they hold, and what is left is its per-millisecond
        arithmetic: the same expressions in the same order as the full tick's."""
        (_dt, lag, vmax, feed, threshold, window, monitor, target, levels_cache, fe_window,
         fe_timeout, theta_zero) = cruise
        plant = self.plant
        # SpeedMonitor.follow_speed, as at the full tick's start
        if abs(plant.omega * feed) <= threshold:
            if monitor.below_threshold_since_us is None:
                monitor.below_threshold_since_us = self._t_us - round(dt * 1e6)
        else:
            monitor.below_threshold_since_us = None
        theta_before, velocity_before = plant.theta, trajectory.velocity
        # the speed window timer (target == commanded: Velocity.step plans nothing)
        actual = plant.omega * feed
        monitor.in_window_ms = monitor.in_window_ms + dt * 1e3 \
            if abs(target - actual) <= window else 0.0
        # Trajectory.advance inside the cruise (the caller checked that it is one)
        trajectory._elapsed = elapsed = trajectory._elapsed + dt
        trajectory.velocity = v0 = segment.v0
        trajectory.position = demand = trajectory._segment_start + v0 * elapsed
        # the motor free (a jam is a command: no record)
        follow_demand(plant, demand, lag, vmax, dt)
        blocked, theta = plant.blocked, plant.theta
        # (inside a cruise the plan goes on: no standstill ends a quick stop here)
        accel = (trajectory.velocity - velocity_before) / dt
        if dt == 0.001 and not blocked:
            _meter_1ms(self, accel)
        else:
            self.meter.update(self, accel, dt)
        g = self.geometry
        if self._levels_cache is levels_cache and levels_cache[1] == (
                theta <= g.neg_limit, theta >= g.pos_limit, theta >= g.home_switch):
            # The recorded tick's levels: no start edge, the latch idle, no limit input
            # active, no crossing to observe (a velocity mode). Nothing in this tick could
            # change the state or a register, so the following-error and R06 checks read
            # the recorded values (the same numbers as floats). An alarm ends the jog (Fault
            # or its reaction): no record from here, since ServoDrive.step drops it only
            # between steps and a step of more than 1 ms runs its next tick straight on.
            if fe_window is not None and abs((trajectory.position - theta) * feed) > fe_window:
                self._fe_ms += dt * 1e3
                if self._fe_ms > fe_timeout:
                    self._fe_ms = 0.0
                    self._cruise = None
                    self.raise_alarm(16)
                    self._s32_check(plant)  # alarm 16 may have changed what it reads
                    return
            else:
                self._fe_ms = 0.0
            if abs((theta - theta_zero) * feed) > S32_MAX:
                self._cruise = None
                self.raise_alarm(15)
            return
        # a switch moved: the inputs' part of the full tick, and no record from here
        self._cruise = None
        self._inputs_tick(self.wired, theta_before, theta)
        regs = self.regs  # _check_following_error, as in the full tick
        window, feed = regs[_FOLLOWING_ERROR_WINDOW], regs[_FEED_CONSTANT]
        if self.state is _ENABLED and window != DISABLED_32 and abs(
                (trajectory.position - plant.theta) * (feed if feed >= 1 else 1)) > window:
            self._fe_ms += dt * 1e3
            if self._fe_ms > regs[_FOLLOWING_ERROR_TIMEOUT]:
                self._fe_ms = 0.0
                self.raise_alarm(16)
        else:
            self._fe_ms = 0.0
        self._s32_check(plant)  # again: alarm 16 may have changed what it reads

    def _s32_check(self: ServoDrive, plant: Plant) -> None:
        feed = self.regs[_FEED_CONSTANT]
        if abs((plant.theta - self.theta_zero) * (feed if feed >= 1 else 1)) > S32_MAX:
            self.raise_alarm(15)  # the position no longer fits R06 (S32)

    def _inputs_tick(self: ServoDrive, wired: dict[str, bool], theta_before: float,
                     theta_after: float) -> bool:
        """The inputs' part of a tick, after the motion: the levels, the start edge, the
        latch, homing's crossings, the limit switches' alarms. True when it did nothing and
        would do nothing again with the same levels (a cruise may be recorded)."""
        trajectory, idle = self.trajectory, True
        g = self.geometry  # geometry.switches(theta_after), inline
        switches = (theta_after <= g.neg_limit, theta_after >= g.pos_limit,
                    theta_after >= g.home_switch)
        before, cached = self._levels, self._levels_cache
        if cached is not None and cached[1] == switches and cached[0] == wired:
            levels = cached[2]  # input_levels(): the last tick's dict, nothing changed
        else:
            levels = self.levels_at(switches)
            self._levels_cache = (dict(wired), switches, levels)
        if levels["start"] and not before.get("start", False):
            idle = False
            self.mode_logic.on_start_input(self)
        self._levels = levels
        latch, latch_level = self.latch, levels["latch"]
        if latch_level or latch.level or latch.rose_at_us is not None:  # else a no-op
            idle = False
            confirmed = latch.update(latch_level, self._t_us, self.position_user)
            if confirmed is not None:
                self.regs[_LATCHED_POSITION] = confirmed
                self.latched_flag = True
        mode = self.mode_logic
        if type(mode).observe is not _NO_OBSERVER:  # the crossings are for homing only
            idle = False
            mode.observe(self, self._changes(before, levels, theta_before, theta_after))
        neg_limit, pos_limit = levels["neg_limit"], levels["pos_limit"]
        # Alarms 20 / 21 (LS1 / LS2): moving into an active limit switch outside homing, a
        # switch the homing method in force (R18 now) uses; else the pin is a digital input
        # (limits_used). With no limit input active there is nothing to check.
        if (neg_limit or pos_limit) and self.state is _ENABLED:
            mode = self.mode_logic
            if type(mode).busy is _NEVER_BUSY or not mode.busy:
                used = _limits_used(self.regs[_HOMING_METHOD])
                velocity = trajectory.velocity
                if neg_limit and velocity < 0.0 and "neg_limit" in used:
                    self.raise_alarm(20)
                elif pos_limit and velocity > 0.0 and "pos_limit" in used:
                    self.raise_alarm(21)
        return idle and self._levels is before and not (neg_limit or pos_limit)

    def _changes(self: ServoDrive, before: dict[str, bool], after: dict[str, bool],
                 theta0: float, theta1: float) -> Changes:
        """Switch edges and markers of this tick, each at the position it happened."""
        g = self.geometry
        edges = {"neg_limit": g.neg_limit, "pos_limit": g.pos_limit, "home": g.home_switch}
        found = []
        for name in SWITCHES:
            if before.get(name, after[name]) != after[name]:
                edge = edges[name]
                at = edge if min(theta0, theta1) <= edge <= max(theta0, theta1) else theta1
                found.append((name, after[name], at))
        found += [("marker", True, m) for m in g.markers_between(theta0, theta1)]
        return sorted(found, key=lambda change: abs(change[2] - theta0))


def _meter_1ms(drive: ServoDrive, accel: float) -> None:
    """CurrentMeter.update for a 1 ms tick in torque with the motor free (the full tick's and
    the cruise tick's case): the same expressions in the same order (readings.py)."""
    meter, config = drive.meter, drive.config
    inertia = 1.0 + config.load_inertia
    torque = 5.0 + 50.0 * abs(accel) / config.quick_stop_decel * inertia
    cap = 3.0 * drive.params[5]  # d5 caps the current
    meter.instant = instant = cap if cap < torque else torque
    mean_square = meter._mean_square
    meter._mean_square = mean_square = mean_square + (instant ** 2 - mean_square) * _K_1MS
    meter.rms = rms = _sqrt(mean_square)
    overload = 100.0 * (rms / 100.0) ** 2
    meter.overload = 999.0 if overload > 999.0 else overload
