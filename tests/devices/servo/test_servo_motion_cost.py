"""A moving drive's step (docs/servo-drive.md §Step cost in motion) does exactly what it did
before that work.

The step of a drive in motion lost its small helpers (properties and methods called every
tick, now written out where the tick needs them), re-reads no attribute chain it already
holds, and keeps two values that only change on a write: the position loop's lag (a function
of parameter i1 alone, cached with the i1 it was computed for) and the current meter's filter
constant at 1 ms. Below, the plain code of every part that changed (the drive's step loop, the
trajectory's advance, the plant, the current meter, the velocity mode and its speed monitor)
runs a seeded random workload with writes in the middle of the motion (i1, the feed constant,
the current cap, the windows, the profile, Select with aux_in_1, other step lengths); the
drive of today must give the same events, snapshots and full state after every stretch.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from test_servo_step_cost import RECOVER, Op, PlainDrive, outcome, random_ops

from app.rig import Rig
from devices.flash import MemoryFlash
from devices.servo import readings
from devices.servo.drive import DriveConfig, ServoDrive
from devices.servo.modes import SpeedMonitor, Velocity
from devices.servo.motion import Trajectory
from devices.servo.plant import COAST_TIME_CONSTANT_S, SETTLED_REV, STOPPED_REV_S, Plant
from devices.servo.readings import JAM_CURRENT, RMS_TIME_CONSTANT_S, CurrentMeter
from devices.servo.registers import R
from devices.servo.stillness import may_settle, state_key

TICK_US = 1_000


# ---- the parts as they were before the work (plain: every helper called) --------------------
class PlainStepDrive(PlainDrive):
    """The plain tick (test_servo_step_cost.py) under the step loop as it was."""

    def step(self, now_us: int) -> None:
        if now_us < self._t_us:
            raise ValueError(f"{self.device_id}: time went backwards")
        span, alarms, still = now_us - self._t_us, self.alarms, self._still
        if span == still.dt and not self._touched and alarms is still.alarms \
                and alarms.changes == still.changes and self.SKIP_STILL:
            self._t_us = self.now_us = now_us
            return
        if self._touched:
            self._touched = False
            still.restart()
        before = state_key(self) if span and self.plant.omega == 0.0 and may_settle(self) \
            and still.due() else None
        queued = len(self.events.items)
        while self._t_us < now_us:
            dt_us = min(TICK_US, now_us - self._t_us)
            self._t_us += dt_us
            self.now_us = self._t_us
            self._tick(dt_us / 1e6)
        self.now_us = now_us
        settled = False
        if before is not None:
            settled = (not self._touched and len(self.events.items) == queued
                       and may_settle(self) and state_key(self) == before)
            still.checked(settled)
        still.dt = span if settled else None
        still.alarms, still.changes = self.alarms, self.alarms.changes


def plain_plant_step(self: Plant, dt: float, demand: float | None, lag: float,
                     vmax: float = math.inf) -> None:
    before = self.theta
    if self.jammed:
        self.omega = 0.0
        self._last_demand = demand
        return
    if demand is None:
        self.omega *= math.exp(-dt / COAST_TIME_CONSTANT_S)
        if abs(self.omega) < STOPPED_REV_S:
            self.omega = 0.0
        new = self.theta + self.omega * dt
    else:
        previous = self._last_demand if self._last_demand is not None else demand
        rate = (demand - previous) / dt if dt > 0.0 else 0.0
        decay = math.exp(-dt / lag) if lag > 0.0 else 0.0
        new = demand - rate * lag + (self.theta - previous + rate * lag) * decay
        if abs(demand - new) < SETTLED_REV:
            new = demand
        if new - before > vmax * dt:  # the speed loop saturates at Vmax (d3)
            new = before + vmax * dt
        elif before - new > vmax * dt:
            new = before - vmax * dt
    self._last_demand = demand
    low, high = self._end_stops
    self.blocked = not low <= new <= high
    self.theta = min(max(new, low), high)
    if demand is not None or self.blocked:
        self.omega = (self.theta - before) / dt if dt > 0.0 else 0.0


def plain_advance(self: Trajectory, dt: float) -> None:
    while dt > 0.0 and not self.idle:
        segment = self._plan[self._index]
        left = segment.duration - self._elapsed
        if dt < left:
            self._elapsed += dt
            dt = 0.0
            covered, self.velocity = segment.at(self._elapsed)
            self.position = self._segment_start + covered
        else:
            dt -= left
            self._segment_start += segment.distance
            self.position, self.velocity = self._segment_start, segment.v1
            self._index += 1
            self._elapsed = 0.0
    if self.idle and self.target is not None and self.velocity == 0.0:
        self.position = self.target


def plain_meter_update(self: CurrentMeter, d: ServoDrive, accel: float, dt: float) -> None:
    if d.state.in_torque:
        inertia = 1.0 + d.config.load_inertia
        torque = 5.0 + 50.0 * abs(accel) / d.config.quick_stop_decel * inertia
        if d.plant.jammed or d.plant.blocked:
            torque += JAM_CURRENT * min(abs(d.following_error_user) / d.feed, 1.0)
        self.instant = min(torque, 3.0 * d.params[5])
    else:
        self.instant = 0.0
    k = 1.0 - math.exp(-dt / RMS_TIME_CONSTANT_S)
    self._mean_square += (self.instant ** 2 - self._mean_square) * k
    self.rms = math.sqrt(self._mean_square)
    self.overload = min(100.0 * (self.rms / 100.0) ** 2, 999.0)


def plain_monitor_update(self: SpeedMonitor, d: ServoDrive, target: float, dt: float) -> None:
    actual = d.velocity_user
    in_window = abs(target - actual) <= d.reg(R.VELOCITY_WINDOW)
    self.in_window_ms = self.in_window_ms + dt * 1e3 if in_window else 0.0
    # zero speed (the threshold timer) is the drive tick's, every tick: PlainDrive


def plain_target_user(self: Velocity, d: ServoDrive) -> float:
    return d.reg(R.AUX_IN_1) if d.input_level("select") else d.reg(R.TARGET_VELOCITY)


def plain_velocity_step(self: Velocity, d: ServoDrive, dt: float) -> None:
    target = self.target_user(d)
    if target != self.commanded:
        self.commanded = target
        vmax = d.motor_vmax_rev
        velocity = max(-vmax, min(vmax, d.speed_to_rev(target)))
        d.trajectory.run_at(velocity, d.limits(vmax=vmax))
    plain_monitor_update(self.monitor, d, target, dt)


@contextmanager
def plain_parts() -> Iterator[None]:
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Plant, "step", plain_plant_step)
        mp.setattr(Trajectory, "advance", plain_advance)
        mp.setattr(CurrentMeter, "update", plain_meter_update)
        mp.setattr(Velocity, "step", plain_velocity_step)
        mp.setattr(Velocity, "target_user", plain_target_user)
        yield


# ---- the workload: motion, with writes in the middle of it ----------------------------------
def motion_ops(rng: random.Random) -> list[Op]:
    """A jog (or the analog reference) from a recovered drive, or a write while it moves."""
    if rng.random() < 0.3:
        start: list[list[Op]] = [
            [("jog", {"direction": rng.choice((-1, 1))})],
            [("set_mode", {"mode": -127}),
             ("analog_input", {"volts": rng.choice((-7.5, 3.0, 10.0))})],
            # homing onto the negative limit: the limit check must leave it alone
            [("write_register", {"register": 18, "value": rng.choice((1, 17))}), ("home", {})],
        ]
        return [*RECOVER, *rng.choice(start)]
    writes: list[Op] = [
        ("write_parameter", {"parameter": "i1", "value": rng.randint(1, 99)}),  # the lag
        ("write_parameter", {"parameter": "d5", "value": rng.randint(1, 99)}),  # current cap
        ("write_parameter", {"parameter": "d3", "value": rng.randint(1, 99)}),  # vmax
        ("write_register", {"register": 2, "value": rng.choice((0, 1, 60, 6000, 12345))}),
        ("write_register", {"register": 3, "value": rng.choice((0, 50, 2000, 0xFFFF_FFFF))}),
        ("write_register", {"register": 4, "value": rng.choice((0, 5, 100))}),
        ("write_register", {"register": 10, "value": rng.choice((1, 100, 5000))}),
        ("write_register", {"register": 12, "value": rng.choice((3000, 12000, 30000))}),
        ("write_register", {"register": 13, "value": rng.randint(-30_000, 30_000)}),
        ("write_register", {"register": 14, "value": rng.choice((0, 50, 0xFFFF))}),
        ("write_register", {"register": 16, "value": rng.choice((0, 500, 0xFFFF))}),
        ("write_register", {"register": 27, "value": rng.choice((0, -1, -2))}),
        ("write_register", {"register": 30, "value": rng.randint(-20_000, 20_000)}),
        ("set_input", {"name": "select", "value": rng.random() < 0.5}),
        ("jam_load", {"active": rng.random() < 0.3}),
        ("analog_input", {"volts": rng.uniform(-10.0, 10.0)}),
        ("jog", {"direction": rng.choice((-1, 0, 1))}),
        ("stop", {}),
    ]
    return [rng.choice(writes)]


Trace = list[tuple[Any, ...]]


def run(seed: int, stretches: int, ops: Callable[[random.Random], list[Op]],
        drive_class: type[ServoDrive]) -> tuple[Trace, int]:
    """Every stretch: the outcome of each op, the events of each step, the snapshot and the
    full state at its end; and the number of steps that moved."""
    rng = random.Random(seed)
    config = DriveConfig(start_position=-57_000.0)  # half a turn from the negative limit
    drive = drive_class("drive", random.Random(7), config, MemoryFlash())
    rig = Rig("rig", {"drive": drive})
    trace: Trace = []
    t_us, moving = 0, 0
    for _ in range(stretches):
        done = [(op, outcome(rig, op)) for op in ops(rng)]
        dt = rng.choice((1000, 1000, 1000, 250, 1500, 2500))
        events = []
        for _ in range(rng.choice((1, 5, 50, 400))):
            t_us += dt
            drive.step(t_us)
            events.append(drive.drain_events())
            moving += drive.plant.omega != 0.0
        trace.append((done, events, drive.snapshot(), state_key(drive)))
    return trace, moving


def same_runs(seed: int, stretches: int, ops: Callable[[random.Random], list[Op]]) -> int:
    with plain_parts():
        plain, _ = run(seed, stretches, ops, PlainStepDrive)
    fast, moving = run(seed, stretches, ops, ServoDrive)
    for n, (a, b) in enumerate(zip(fast, plain, strict=True)):
        assert a == b, f"stretch {n}: {a[0]}"
    return moving


@pytest.mark.parametrize("seed", [1, 2, *(pytest.param(s, marks=pytest.mark.full)
                                          for s in (3, 4, 5, 6))])
def test_a_moving_drive_steps_as_the_plain_code(seed: int) -> None:
    assert same_runs(seed, 150, motion_ops) > 5_000  # the axis did move


@pytest.mark.parametrize("seed", [11, *(pytest.param(s, marks=pytest.mark.full)
                                        for s in (12, 13))])
def test_every_mode_steps_as_the_plain_code(seed: int) -> None:
    """The random commands of test_servo_step_cost (homing, moves, the interpolator, the
    electronic axis, alarms, power, saves) against the plain parts as well."""
    assert same_runs(seed, 100, random_ops) > 1_000


def jogging_drive() -> tuple[ServoDrive, Rig, int]:
    """A drive booted for 100 ms, then enabled and jogging forwards; and the time it is at."""
    drive = ServoDrive("drive", random.Random(7), DriveConfig(), MemoryFlash())
    rig = Rig("rig", {"drive": drive})
    t_us = 0
    for _ in range(100):
        t_us += 1000
        drive.step(t_us)
    rig.apply("drive", "enable", {"on": True})
    rig.apply("drive", "jog", {"direction": 1})
    return drive, rig, t_us


def test_the_lag_follows_a_write_of_i1_at_the_next_tick() -> None:
    """The cached lag is the one of the i1 in force: written mid-jog, the next tick uses it."""
    drive, rig, t_us = jogging_drive()
    for i1 in (50, 10, 99, 50):
        rig.apply("drive", "write_parameter", {"parameter": "i1", "value": i1})
        for _ in range(30):
            t_us += 1000
            theta, last = drive.plant.theta, drive.plant._last_demand
            drive.step(t_us)
            assert drive._lag_cache == (i1, drive.position_lag_s)
            demand, lag = drive.trajectory.position, drive.position_lag_s
            last = demand if last is None else last
            rate = (demand - last) / 0.001
            new = demand - rate * lag + (theta - last + rate * lag) * math.exp(-0.001 / lag)
            assert drive.plant.theta == (demand if abs(demand - new) < SETTLED_REV else new)
    assert drive.plant.omega > 0.0


def test_the_meter_constant_at_1_ms_is_the_computed_one() -> None:
    k = 1.0 - math.exp(-(1000 / 1e6) / RMS_TIME_CONSTANT_S)  # dt as the drive's step makes it
    assert k == readings._K_1MS


def test_a_cruising_tick_calls_none_of_the_parts() -> None:
    """The tick's inline copies (session 10: Velocity.step, Trajectory.advance in a cruise,
    Plant.step following a demand, CurrentMeter.update at 1 ms) are what a jog runs: the
    differential tests above then compare them, not the methods, with the plain code."""
    drive, _rig, t_us = jogging_drive()
    for _ in range(1500):  # up to speed, cruising
        t_us += 1000
        drive.step(t_us)
    calls: list[str] = []
    with pytest.MonkeyPatch.context() as mp:
        def spied(name: str, method: Callable[..., Any]) -> Callable[..., Any]:
            def spy(*args: Any) -> Any:
                calls.append(name)
                return method(*args)
            return spy

        for cls, name in ((Plant, "step"), (Trajectory, "advance"), (CurrentMeter, "update"),
                          (Velocity, "step"), (Velocity, "target_user")):
            mp.setattr(cls, name, spied(name, getattr(cls, name)))
        for _ in range(100):
            t_us += 1000
            drive.step(t_us)
    assert drive.plant.omega > 0.0 and drive.trajectory.velocity > 0.0
    assert calls == []
