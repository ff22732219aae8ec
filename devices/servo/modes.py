"""Modes of operation (R01 / 0x6060): what each one does with the demand position.

Seed 004 ch. 1 (R00 / R05 mode bits), ch. 2 "I/O digitali" (Start, Select, End of Job,
Target per mode) and ch. 4 (objects of each mode, worked examples). The drive calls a mode's
hooks; a mode only plans the :class:`~devices.servo.motion.Trajectory` and keeps its own flags.
Halt, quick stop and the hardware consents are the drive's business: a mode's ``step`` runs
only while motion is allowed, and ``halted`` tells it that a stop took over.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.servo import ds402
from devices.servo.homing import Homing
from devices.servo.mode_base import Mode
from devices.servo.registers import DISABLED_16, R

# Register numbers read every tick (a moving drive): an enum member's lookup is slow.
_AUX_IN_1, _TARGET_VELOCITY = int(R.AUX_IN_1), int(R.TARGET_VELOCITY)
_VELOCITY_WINDOW = int(R.VELOCITY_WINDOW)
_FEED_CONSTANT = int(R.FEED_CONSTANT)

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive


class Positioner(Mode):
    """Mode 1: point to point, absolute or incremental, buffered or on the fly."""

    number = 1

    def __init__(self) -> None:
        self.move_target: int | None = None  # user units
        self.pending: int | None = None
        self.last_target: int | None = None
        self.eoj = False
        self.sp_ack = False
        #: the target of the last start: Near to target measures from it until the next start
        #: (ch. 2 "Target": lowered at the start only; a stop or torque off does not)
        self.started_target: int | None = None

    def enter(self, d: ServoDrive) -> None:
        super().enter(d)
        self.move_target = self.pending = self.started_target = None
        self.last_target = d.position_user

    def torque_on(self, d: ServoDrive) -> None:
        self.move_target = self.pending = None
        self.last_target = d.position_user

    def on_controlword(self, d: ServoDrive, rising: int, falling: int) -> None:
        if rising & ds402.CW_NEW_SET_POINT:
            self.new_set_point(d)
        if falling & ds402.CW_NEW_SET_POINT:
            self.sp_ack = False

    def on_start_input(self, d: ServoDrive) -> None:
        self.new_set_point(d)

    def new_set_point(self, d: ServoDrive) -> None:
        if not d.motion_allowed:
            # Pos_str returns to zero by itself (ch. 2) even when the drive cannot start:
            # the start is consumed, so the master's next Pos_str is a fresh 0 -> 1 edge
            d.set_point_taken()
            return
        value = d.reg(R.AUX_IN_1) if d.input_level("select") else d.reg(R.TARGET_POSITION)
        if d.cw & ds402.CW_RELATIVE:  # from the last target, or from here after a stop
            has_base = self.move_target is not None and self.last_target is not None
            value += self.last_target if has_base else d.position_user
        self.sp_ack = not d.set_point_taken()  # the register view's Pos_str clears itself
        self.last_target = value
        if self.move_target is not None and not d.trajectory.idle \
                and not d.cw & ds402.CW_CHANGE_IMMEDIATELY:
            self.pending = value  # finishes the current move first; sp_rdy drops
        else:
            self.pending = None
            self.go(d, value)

    def go(self, d: ServoDrive, target: int) -> None:
        self.move_target = self.started_target = target
        self.eoj = False
        d.trajectory.move_to(d.user_to_rev(target), d.limits())

    def step(self, d: ServoDrive, dt: float) -> None:
        if self.pending is not None and d.trajectory.idle:
            target, self.pending = self.pending, None
            self.go(d, target)
        if self.move_target is not None and not self.eoj and d.trajectory.at_target \
                and d.following_error_below_window:
            self.eoj = True

    def halted(self, d: ServoDrive) -> None:
        self.move_target = self.pending = None

    def flags(self, d: ServoDrive) -> dict[str, bool]:
        # sp_rdy, "pronto per un nuovo set-point" (ch. 1): a start now would be taken, so not
        # while a Pos_str would be consumed and lost (no torque, motion off, stop, alarm)
        ready = self.pending is None and d.motion_allowed
        return {"set_point_ready": ready, "set_point_ack": self.sp_ack,
                "end_of_job": self.eoj, "following_error": d.following_error_exceeded}

    def end_of_job(self, d: ServoDrive) -> bool:
        return self.eoj

    def near_target(self, d: ServoDrive) -> bool:
        window, target = d.reg(R.TARGET_WINDOW), self.started_target
        return target is not None and abs(target - d.position_user) < window

    def target_reached(self, d: ServoDrive) -> bool:
        return super().target_reached(d) and (self.move_target is None or self.eoj)


class PulsePositioner(Positioner):
    """Mode -1: each pulse of the pulse input is a new start (docs/servo-drive.md §Modes)."""

    number = -1

    def pulses(self, d: ServoDrive, count: int) -> None:
        if not d.motion_allowed or count == 0:
            return
        quantum = d.reg(R.FEED_CONSTANT) * d.reg(R.GEAR_RATIO_NUMERATOR) \
            / (d.reg(R.GEAR_RATIO_DIVISOR) * d.reg(R.MASTER_ENCODER_INCREMENTS))
        base = self.last_target if self.last_target is not None else d.position_user
        self.last_target = round(base + count * quantum)
        self.pending = None
        self.go(d, self.last_target)

    def near_target(self, d: ServoDrive) -> bool:
        # ch. 2: the Target output serves mode 1 (and the SAP positioner), not mode -1
        return False


class SpeedMonitor:
    """Velocity window (R14/R15, 0x606D/E) and threshold (R16/R17, 0x606F/0x6070) timers.

    The window timer counts while the mode runs (its target is the command's). The threshold
    timer is zero speed, ch. 1 R05 bit 7 "velocità nulla: 1: asse fermo": it follows the axis
    every tick of a velocity mode, whatever stopped it or keeps it still (stop, Ien, torque
    off). It is kept as the time the speed went within the threshold, not as a count, so a
    standing axis changes nothing tick after tick (still steps and quiet spans,
    docs/servo-drive.md) and the flag is read off the clock.
    """

    # Slots: read every tick of a moving drive, and a __dict__ read once (a stillness key)
    # would slow each access for good on CPython 3.11 (devices/stillness.py slot_names).
    __slots__ = ("below_threshold_since_us", "in_window_ms")

    def __init__(self) -> None:
        self.in_window_ms = 0.0
        #: start of the first tick of the current run within R16, us; None outside it
        self.below_threshold_since_us: int | None = None

    def follow_speed(self, d: ServoDrive, tick_start_us: int) -> None:
        """Every tick, at its start (ticking.py has this written out)."""
        if abs(d.velocity_user) <= d.reg(R.VELOCITY_THRESHOLD):
            if self.below_threshold_since_us is None:
                self.below_threshold_since_us = tick_start_us
        else:
            self.below_threshold_since_us = None

    def zero_speed_at(self, d: ServoDrive) -> int | None:
        """When zero speed comes on if the speed stays within the threshold; None if it
        cannot (above the threshold, or the check disabled)."""
        since = self.below_threshold_since_us
        if since is None or d.reg(R.VELOCITY_THRESHOLD) == DISABLED_16:
            return None
        return since + 1000 * d.reg(R.VELOCITY_THRESHOLD_TIME)

    def reached(self, d: ServoDrive) -> bool:
        if d.reg(R.VELOCITY_WINDOW) == DISABLED_16:
            return d.trajectory.cruising
        return self.in_window_ms >= d.reg(R.VELOCITY_WINDOW_TIME)

    def zero_speed(self, d: ServoDrive) -> bool:
        at = self.zero_speed_at(d)
        return at is not None and d.now_us >= at


class Velocity(Mode):
    """Mode 3: run at target_velocity (R13 / 0x60FF), or aux_in_1 (R30) with Select high."""

    number = 3

    def __init__(self) -> None:
        self.commanded: float | None = None
        self.monitor = SpeedMonitor()

    def target_user(self, d: ServoDrive) -> float:
        # d.input_level("select"): the wiring alone, select is no switch
        return d.regs[_AUX_IN_1] if d.wired.get("select", False) else d.regs[_TARGET_VELOCITY]

    def enter(self, d: ServoDrive) -> None:
        super().enter(d)
        self.commanded = None

    def step(self, d: ServoDrive, dt: float) -> None:
        target = self.target_user(d)
        if target != self.commanded:
            self.commanded = target
            vmax = d.motor_vmax_rev
            velocity = max(-vmax, min(vmax, d.speed_to_rev(target)))
            d.trajectory.run_at(velocity, d.limits(vmax=vmax))
        # the speed window timer, here (every tick of a jog: no call); the threshold timer
        # follows the axis in any state (ticking.py)
        monitor, regs = self.monitor, d.regs
        feed = regs[_FEED_CONSTANT]
        actual = d.plant.omega * (feed if feed >= 1 else 1)  # d.velocity_user
        monitor.in_window_ms = monitor.in_window_ms + dt * 1e3 \
            if abs(target - actual) <= regs[_VELOCITY_WINDOW] else 0.0

    def halted(self, d: ServoDrive) -> None:
        self.commanded = None

    def flags(self, d: ServoDrive) -> dict[str, bool]:
        return {"zero_speed": self.monitor.zero_speed(d)}

    def end_of_job(self, d: ServoDrive) -> bool:
        return self.commanded is not None and d.trajectory.cruising

    def target_reached(self, d: ServoDrive) -> bool:
        if self.commanded is None:
            return super().target_reached(d)
        return self.monitor.reached(d)


class AnalogReference(Velocity):
    """Mode -127: speed from the analog reference, +-10 V = +-Vmax (d3). End of Job low."""

    number = -127

    def target_user(self, d: ServoDrive) -> float:
        return d.analog_volts / 10.0 * d.motor_vmax_rev * d.feed

    def end_of_job(self, d: ServoDrive) -> bool:
        return False


class Interpolator(Mode):
    """Mode 7: a set-point per interpolation period (R47 / 0x60C2:1, ms), linear in between."""

    number = 7

    def __init__(self) -> None:
        self.active = False
        self.previous = self.next = 0.0
        self.elapsed = 0.0

    def period_s(self, d: ServoDrive) -> float:
        return max(d.reg(R.IP_TIME_UNITS), 1) / 1e3

    def step(self, d: ServoDrive, dt: float) -> None:
        wanted = bool(d.cw & ds402.CW_NEW_SET_POINT)
        if wanted and not self.active:
            self.active, self.elapsed = True, 0.0
            self.previous = self.next = d.trajectory.position
            # The set-point starts where the axis stands: ch. 4 has the master send its first
            # one after the activation (the loop's "write Sync" comes first), so one left
            # from before (0x60C1:1's power-on 0, a previous run) would throw the axis there.
            d.ip_set_point = round((d.trajectory.position - d.theta_zero) * d.feed)
        elif not wanted and self.active:
            self.active = False
            d.trajectory.stop(d.limits())
        if not self.active:
            return
        period = self.period_s(d)
        self.elapsed += dt
        while self.elapsed >= period - 1e-12:
            self.elapsed -= period
            self.previous, self.next = self.next, d.user_to_rev(d.ip_set_point)
        share = min(self.elapsed / period, 1.0)
        d.trajectory.hold(self.previous + (self.next - self.previous) * share,
                          (self.next - self.previous) / period)

    def sync(self, d: ServoDrive) -> None:
        """A bus Sync: take the set-point now and restart the period."""
        if self.active:
            self.previous, self.next = d.trajectory.position, d.user_to_rev(d.ip_set_point)
            self.elapsed = 0.0

    def halted(self, d: ServoDrive) -> None:
        self.active = False

    def flags(self, d: ServoDrive) -> dict[str, bool]:
        return {"ip_active": self.active, "following_error": d.following_error_exceeded}


class ElectronicAxis(Mode):
    """Mode -2: the slave follows the master encoder through the gear ratio R25 / R26."""

    number = -2

    def __init__(self) -> None:
        self.engaged = False

    def step(self, d: ServoDrive, dt: float) -> None:
        engaged = d.input_level("start") and bool(d.cw & ds402.CW_AXIS_START)
        if engaged:
            ratio = d.reg(R.GEAR_RATIO_NUMERATOR) / d.reg(R.GEAR_RATIO_DIVISOR)
            master_rev_s = d.master_rpm / 60.0
            d.trajectory.hold(d.trajectory.position + master_rev_s * ratio * dt,
                              master_rev_s * ratio)
        elif self.engaged:
            d.trajectory.stop(d.limits())  # "held in torque": stop, then stand still
        self.engaged = engaged

    def halted(self, d: ServoDrive) -> None:
        self.engaged = False

    def flags(self, d: ServoDrive) -> dict[str, bool]:
        return {"axis_started": self.engaged}


class SaveLoad(Mode):
    """Mode -50: R00 bit 5 0 -> 1 saves to flash, bit 6 0 -> 1 loads (the drive does both)."""

    number = -50


MODE_CLASSES: dict[int, type[Mode]] = {cls.number: cls for cls in (
    Positioner, Velocity, Homing, Interpolator, PulsePositioner, ElectronicAxis, SaveLoad,
    AnalogReference)}
