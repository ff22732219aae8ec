"""Trajectory generation: trapezoidal, S (jerk) and sine ramps, planned from any motion state.

Units inside the model are motor revolutions, rev/s and rev/s^2 (docs/servo-drive.md §Motion).
A plan is a list of :class:`Ramp` segments. A ramp changes the velocity from ``v0`` to ``v1``
in ``duration`` seconds; its shape (R27 / 0x6086: 0 trapezoidal, -1 S, -2 sine, seed 004 ch. 4)
only changes how the velocity moves in between. Every shape is symmetric, so a ramp covers
``duration * (v0 + v1) / 2`` whatever its shape, and the ramp time is ``|v1 - v0| / a`` for all
of them: the profile acceleration is the mean acceleration of a ramp (the seed's "100 ms from 0
to 200 rpm" holds for every profile). For the S ramp the jerk registers R28 / R29 (1..99) are
the percentage of the ramp spent changing the acceleration.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

EPS_REV = 1e-9


class Shape(enum.IntEnum):
    TRAPEZOIDAL = 0
    S_CURVE = -1
    SINE = -2


def shape_s(shape: Shape, fraction: float, u: float) -> float:
    """Normalised velocity (0..1) at normalised time u of a ramp."""
    if shape is Shape.SINE:
        return (1.0 - math.cos(math.pi * u)) / 2.0
    if shape is Shape.S_CURVE and fraction > 0.0:
        h = fraction / 2.0
        a = 1.0 / (1.0 - h)
        if u <= h:
            return a * u * u / (2.0 * h)
        if u <= 1.0 - h:
            return a * h / 2.0 + a * (u - h)
        return 1.0 - shape_s(shape, fraction, 1.0 - u)
    return u


def shape_integral(shape: Shape, fraction: float, u: float) -> float:
    """Integral of :func:`shape_s` from 0 to u (1/2 at u = 1 for every shape)."""
    if shape is Shape.SINE:
        return u / 2.0 - math.sin(math.pi * u) / (2.0 * math.pi)
    if shape is Shape.S_CURVE and fraction > 0.0:
        h = fraction / 2.0
        a = 1.0 / (1.0 - h)
        if u <= h:
            return a * u ** 3 / (6.0 * h)
        if u <= 1.0 - h:
            s_h = a * h / 2.0
            return a * h * h / 6.0 + s_h * (u - h) + a * (u - h) ** 2 / 2.0
        return u - 0.5 + shape_integral(shape, fraction, 1.0 - u)
    return u * u / 2.0


@dataclass(frozen=True)
class Ramp:
    duration: float  # s; math.inf for an endless cruise
    v0: float
    v1: float
    shape: Shape = Shape.TRAPEZOIDAL
    fraction: float = 0.0  # S ramp: share of the ramp with changing acceleration

    @property
    def distance(self) -> float:
        if math.isinf(self.duration):
            raise ValueError("an endless cruise has no length")
        return self.duration * (self.v0 + self.v1) / 2.0

    def at(self, t: float) -> tuple[float, float]:
        """(distance covered, velocity) t seconds into the ramp."""
        if self.v0 == self.v1 or math.isinf(self.duration):
            return self.v0 * t, self.v0
        u = min(max(t / self.duration, 0.0), 1.0)
        dv = self.v1 - self.v0
        return (self.v0 * t + dv * self.duration * shape_integral(self.shape, self.fraction, u),
                self.v0 + dv * shape_s(self.shape, self.fraction, u))


@dataclass(frozen=True)
class Limits:
    """What bounds a plan: speed, acceleration, deceleration (magnitudes) and the ramp shape."""

    vmax: float
    acc: float
    dec: float
    shape: Shape = Shape.TRAPEZOIDAL
    acc_fraction: float = 0.5
    dec_fraction: float = 0.5


def ramp(v0: float, v1: float, lim: Limits) -> Ramp:
    """A ramp at the acceleration (speeding up) or deceleration (slowing down) of ``lim``."""
    speeding_up = abs(v1) > abs(v0) and (v0 == 0.0 or (v0 > 0) == (v1 > 0))
    rate = lim.acc if speeding_up else lim.dec
    fraction = lim.acc_fraction if speeding_up else lim.dec_fraction
    duration = abs(v1 - v0) / rate if rate > 0.0 else 0.0
    return Ramp(duration, v0, v1, lim.shape, fraction)


def plan_stop(v0: float, lim: Limits) -> list[Ramp]:
    return [ramp(v0, 0.0, lim)] if v0 != 0.0 else []


def plan_velocity(v0: float, target: float, lim: Limits) -> list[Ramp]:
    """Ramp to ``target`` (through zero at the deceleration when the sign changes), then cruise."""
    plan: list[Ramp] = []
    if v0 != 0.0 and target != 0.0 and (v0 > 0) != (target > 0):
        plan.append(ramp(v0, 0.0, lim))
        v0 = 0.0
    if target != v0:
        plan.append(ramp(v0, target, lim))
    plan.append(Ramp(math.inf, target, target))
    return plan


def plan_move(p0: float, v0: float, target: float, lim: Limits) -> list[Ramp]:
    """From position p0 at velocity v0 to rest at ``target``, within ``lim``.

    When the target is behind the motion, or too close to stop in front of it, the plan first
    stops (overshooting) and then comes back. With no speed allowed the plan only stops.
    """
    plan: list[Ramp] = []
    if v0 != 0.0:
        stop = ramp(v0, 0.0, lim)
        ahead = target - p0
        if (ahead > 0) != (v0 > 0) or abs(ahead) < abs(stop.distance) - EPS_REV \
                or lim.vmax <= 0.0:
            plan.append(stop)
            p0 += stop.distance
            v0 = 0.0
    distance = target - p0
    if lim.vmax <= 0.0 or (abs(distance) <= EPS_REV and v0 == 0.0):
        return plan
    sign = 1.0 if distance > 0 else -1.0
    length, u0 = abs(distance), abs(v0)
    if u0 > lim.vmax:
        peak = lim.vmax
    elif lim.acc > 0.0 and lim.dec > 0.0:
        peak = math.sqrt((length + u0 * u0 / (2.0 * lim.acc))
                         / (1.0 / (2.0 * lim.acc) + 1.0 / (2.0 * lim.dec)))
    elif lim.dec > 0.0:
        peak = math.sqrt(2.0 * lim.dec * length)
    else:
        peak = lim.vmax
    peak = min(peak, lim.vmax)
    up = ramp(sign * u0, sign * peak, lim)
    down = ramp(sign * peak, 0.0, lim)
    cruise = length - abs(up.distance) - abs(down.distance)
    for segment in (up, Ramp(max(cruise, 0.0) / peak, sign * peak, sign * peak), down):
        if segment.duration > 0.0:
            plan.append(segment)
    return plan


class Trajectory:
    """The demand position and velocity, advanced through a plan."""

    # Slots: read every tick of a moving drive, and a __dict__ read once (a stillness key)
    # would slow each access for good on CPython 3.11 (devices/stillness.py slot_names).
    __slots__ = ("_elapsed", "_index", "_plan", "_segment_start", "position", "target",
                 "velocity")

    def __init__(self, position: float = 0.0) -> None:
        self.position = position
        self.velocity = 0.0
        self.target: float | None = None  # where the current plan comes to rest, if anywhere
        self._plan: list[Ramp] = []
        self._index = 0
        self._elapsed = 0.0
        self._segment_start = position

    @property
    def idle(self) -> bool:
        """No plan left to run (an endless cruise never ends)."""
        return self._index >= len(self._plan)

    @property
    def cruising(self) -> bool:
        """In the endless cruise of a velocity plan: the ramp is over."""
        return self._index == len(self._plan) - 1 and math.isinf(self._plan[-1].duration)

    @property
    def at_target(self) -> bool:
        return self.idle and self.target is not None and abs(self.position - self.target) \
            <= EPS_REV

    def hold(self, position: float, velocity: float = 0.0) -> None:
        """Drop the plan and stand (or move, for followers) at the given state."""
        self.position, self.velocity = position, velocity
        self.target = None
        self._set([])

    def move_to(self, target: float, lim: Limits) -> None:
        there = self.velocity == 0.0 and abs(target - self.position) <= EPS_REV
        # With no speed allowed (R12 = 0) the plan only stops: the target is never reached,
        # so it is not kept, or the landing below and in advance() would jump onto it.
        self.target = target if lim.vmax > 0.0 or there else None
        self._set(plan_move(self.position, self.velocity, target, lim))
        if self.idle and self.velocity == 0.0 and self.target is not None:
            self.position = target

    def run_at(self, velocity: float, lim: Limits) -> None:
        self.target = None
        self._set(plan_velocity(self.velocity, velocity, lim))

    def stop(self, lim: Limits) -> None:
        self.target = None
        self._set(plan_stop(self.velocity, lim))

    def _set(self, plan: list[Ramp]) -> None:
        self._plan, self._index, self._elapsed = plan, 0, 0.0
        self._segment_start = self.position

    def advance(self, dt: float) -> None:
        # the plan is not replaced while advancing; the index and the time into the segment
        # live in locals until the end (every tick of a moving drive)
        plan, index, elapsed = self._plan, self._index, self._elapsed
        count = len(plan)  # index >= count: idle
        while dt > 0.0 and index < count:
            segment = plan[index]
            left = segment.duration - elapsed
            if dt < left:
                elapsed += dt
                dt = 0.0
                v0 = segment.v0
                if v0 == segment.v1:  # a cruise: Ramp.at's first case, inline
                    self.velocity = v0
                    self.position = self._segment_start + v0 * elapsed
                else:
                    covered, self.velocity = segment.at(elapsed)
                    self.position = self._segment_start + covered
            else:
                dt -= left
                self._segment_start += segment.distance
                self.position, self.velocity = self._segment_start, segment.v1
                index += 1
                elapsed = 0.0
        self._index, self._elapsed = index, elapsed
        if index >= count and self.target is not None and self.velocity == 0.0:
            self.position = self.target  # land exactly: the plan's sum carries float error
