"""Profile generator (R27 / 0x6086: 0 trapezoidal, -1 S, -2 sine; seed 004 ch. 4) and the
plant: plans end exactly at the target, within speed and acceleration limits."""

from __future__ import annotations

import math

import pytest

from devices.servo.motion import (
    Limits,
    Ramp,
    Shape,
    Trajectory,
    plan_move,
    plan_velocity,
    shape_integral,
    shape_s,
)
from devices.servo.plant import AxisGeometry, Plant

SHAPES = [(Shape.TRAPEZOIDAL, 0.0), (Shape.S_CURVE, 0.01), (Shape.S_CURVE, 0.5),
          (Shape.S_CURVE, 0.99), (Shape.SINE, 0.0)]


@pytest.mark.parametrize(("shape", "fraction"), SHAPES)
def test_shape_functions(shape: Shape, fraction: float) -> None:
    assert shape_s(shape, fraction, 0.0) == pytest.approx(0.0)
    assert shape_s(shape, fraction, 1.0) == pytest.approx(1.0)
    assert shape_integral(shape, fraction, 1.0) == pytest.approx(0.5)
    n = 2000
    for u in (0.1, 0.37, 0.5, 0.8, 1.0):  # the integral is the integral (midpoint rule)
        numeric = sum(shape_s(shape, fraction, (i + 0.5) / n * u) for i in range(n)) * u / n
        assert shape_integral(shape, fraction, u) == pytest.approx(numeric, abs=1e-6)


@pytest.mark.parametrize(("shape", "fraction", "peak"), [
    (Shape.TRAPEZOIDAL, 0.0, 1.0), (Shape.SINE, 0.0, math.pi / 2),
    (Shape.S_CURVE, 0.5, 1 / 0.75), (Shape.S_CURVE, 0.99, 1 / (1 - 0.495))])
def test_peak_acceleration_of_a_ramp(shape: Shape, fraction: float, peak: float) -> None:
    """Same ramp time for every shape: the S and sine ramps peak above the mean."""
    du = 1e-6
    found = max((shape_s(shape, fraction, u + du) - shape_s(shape, fraction, u)) / du
                for u in (i / 1000 for i in range(1000)))
    assert found == pytest.approx(peak, rel=1e-3)


def _run(plan_target: float, p0: float, v0: float, lim: Limits, dt: float = 1e-3
         ) -> tuple[Trajectory, float, float]:
    traj = Trajectory(p0)
    traj.velocity = v0
    traj.move_to(plan_target, lim)
    top_speed, top_accel, t = 0.0, 0.0, 0.0
    while not traj.idle and t < 100:
        v_before = traj.velocity
        traj.advance(dt)
        top_speed = max(top_speed, abs(traj.velocity))
        top_accel = max(top_accel, abs(traj.velocity - v_before) / dt)
        t += dt
    return traj, top_speed, top_accel


@pytest.mark.parametrize(("shape", "fraction"), SHAPES)
@pytest.mark.parametrize(("p0", "v0", "target"), [
    (0.0, 0.0, 10.0), (0.0, 0.0, -3.0), (0.0, 0.0, 0.01), (0.0, 2.0, 10.0), (0.0, 2.0, 0.1),
    (0.0, 2.0, -5.0), (5.0, -4.0, 6.0), (0.0, 8.0, 20.0), (1.0, 0.0, 1.0)])
def test_moves_end_exactly_at_the_target(shape: Shape, fraction: float, p0: float, v0: float,
                                         target: float) -> None:
    lim = Limits(vmax=3.0, acc=20.0, dec=10.0, shape=shape, acc_fraction=fraction,
                 dec_fraction=fraction)
    traj, top_speed, top_accel = _run(target, p0, v0, lim)
    assert traj.idle and traj.at_target
    assert traj.position == target and traj.velocity == 0.0
    assert top_speed <= max(lim.vmax, abs(v0)) + 1e-9
    bound = {Shape.TRAPEZOIDAL: 1.0, Shape.SINE: math.pi / 2}.get(shape, 1 / (1 - fraction / 2))
    assert top_accel <= 20.0 * bound * 1.01


def test_trapezoid_timing() -> None:
    """Rest to rest over 10 turns at 2 rev/s, 0.1 s ramps: 0.1 + 4.9 + 0.1 s."""
    plan = plan_move(0.0, 0.0, 10.0, Limits(2.0, 20.0, 20.0))
    assert [round(r.duration, 9) for r in plan] == [0.1, 4.9, 0.1]
    assert sum(r.distance for r in plan) == pytest.approx(10.0)


def test_velocity_plan_through_zero() -> None:
    plan = plan_velocity(2.0, -1.0, Limits(5.0, 10.0, 4.0))
    assert plan[0] == Ramp(0.5, 2.0, 0.0, Shape.TRAPEZOIDAL, 0.5)  # decelerate at 4
    assert plan[1].duration == pytest.approx(0.1)  # accelerate at 10
    assert math.isinf(plan[-1].duration) and plan[-1].v0 == -1.0


def test_zero_speed_or_acceleration_never_divides_by_zero() -> None:
    assert plan_move(0.0, 0.0, 5.0, Limits(0.0, 10.0, 10.0)) == []
    traj, _, _ = _run(5.0, 0.0, 0.0, Limits(2.0, 0.0, 0.0))  # instantaneous ramps
    assert traj.position == 5.0


@pytest.mark.parametrize("v0", [0.0, 2.0])
def test_a_move_with_no_speed_allowed_never_reaches_its_target(v0: float) -> None:
    """vmax 0 (R12 profile_velocity = 0, in range 0..0x7FFFFFFF, ch. 1): the demand stops and
    stays; it does not jump to the target, and the move never counts as arrived."""
    traj = Trajectory(1.0)
    traj.velocity = v0
    traj.move_to(5.0, Limits(0.0, 10.0, 10.0))
    for _ in range(2000):
        traj.advance(1e-3)
    assert traj.idle and traj.velocity == 0.0
    assert traj.position == pytest.approx(1.0 + v0 * v0 / 20.0)  # only the stop ramp
    assert not traj.at_target


def test_plant_follows_with_the_position_lag_and_coasts_when_released() -> None:
    plant = Plant(AxisGeometry(-100, 100, 0, 0.25))
    for k in range(1, 1001):  # 1 s of a demand at 1 rev/s, lag 2 ms
        plant.step(1e-3, k * 1e-3, 0.002)
    assert plant.omega == pytest.approx(1.0, rel=1e-3)
    assert 1.0 - plant.theta == pytest.approx(0.002, rel=0.05)  # following error = v * lag
    plant.step(1e-3, None, 0.002)
    speed = plant.omega
    for _ in range(200):
        plant.step(1e-3, None, 0.002)
    assert plant.omega == pytest.approx(speed * math.exp(-1), rel=0.01)


def test_end_stops_block_the_carriage() -> None:
    plant = Plant(AxisGeometry(-1, 1, 0, 0.25, end_margin=0.5))
    plant.step(1e-3, 5.0, 0.0)
    assert plant.theta == 1.5 and plant.blocked


@pytest.mark.parametrize(("a", "b", "markers"), [
    (0.0, 1.0, [0.25]), (0.0, 2.3, [0.25, 1.25, 2.25]), (0.25, 0.25, []), (0.25, 1.25, [1.25]),
    (1.25, 0.25, [0.25]), (0.0, -1.0, [-0.75]), (3.0, 0.0, [2.25, 1.25, 0.25])])
def test_one_marker_per_turn(a: float, b: float, markers: list[float]) -> None:
    assert AxisGeometry(-10, 10, 0, 0.25).markers_between(a, b) == markers
