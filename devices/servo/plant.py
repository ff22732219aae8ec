"""The motor, its load and the axis they move: what the drive controls and what it senses.

Positions are motor revolutions from the rig's origin. The axis has a negative and a positive
limit switch (active at and beyond their positions), a home switch active from its position
upwards (a "positive" home switch in DSP 402 homing terms) and one encoder marker per motor
turn; mechanical end stops sit ``end_margin`` turns beyond the limit switches. In torque the
motor follows the demand with a first-order lag (the position loop, time constant ``lag``);
released it coasts down. It never turns faster than d3's Vmax. A jammed load does not move.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

COAST_TIME_CONSTANT_S = 0.2  # a released motor's speed decays with this time constant
STOPPED_REV_S = 1e-4  # a motor slower than this has stopped (coasting, or ending a stop)
SETTLED_REV = 1e-7  # closer than this the position loop has settled (well below 1 user unit)
_exp = math.exp  # every tick of a drive in torque: no module attribute lookup


@dataclass(frozen=True, slots=True)  # slots: as Plant's
class AxisGeometry:
    neg_limit: float
    pos_limit: float
    home_switch: float
    marker_offset: float  # a marker at marker_offset + k for every integer k
    end_margin: float = 1.0

    @property
    def end_stops(self) -> tuple[float, float]:
        return self.neg_limit - self.end_margin, self.pos_limit + self.end_margin

    def switches(self, theta: float) -> tuple[bool, bool, bool]:
        """(negative limit, positive limit, home switch) as the carriage actuates them."""
        return theta <= self.neg_limit, theta >= self.pos_limit, theta >= self.home_switch

    def markers_between(self, a: float, b: float) -> list[float]:
        """Marker positions crossed going from a to b, in the order they are met.

        Going up a marker at m is crossed when a < m <= b, going down when b <= m < a.
        """
        off = self.marker_offset
        if b > a:
            ks = range(math.floor(a - off) + 1, math.floor(b - off) + 1)
        elif b < a:
            ks = range(math.ceil(a - off) - 1, math.ceil(b - off) - 1, -1)
        else:
            return []
        return [off + k for k in ks]


class Plant:
    # Slots: read every tick of a moving drive, and a __dict__ read once (a stillness key)
    # would slow each access for good on CPython 3.11 (devices/stillness.py slot_names).
    __slots__ = ("_end_stops", "_last_demand", "blocked", "geometry", "jammed", "omega",
                 "theta")

    def __init__(self, geometry: AxisGeometry, position: float = 0.0) -> None:
        self.geometry = geometry
        self.theta = position
        self.omega = 0.0
        self.jammed = False
        self.blocked = False  # against an end stop
        self._last_demand: float | None = None
        self._end_stops = geometry.end_stops  # the geometry is frozen

    @property
    def standstill(self) -> bool:
        """The motor has stopped: what a quick stop or a fault reaction waits for before the
        torque goes off (DSP 402; the demand at rest is not enough, the motor lags it)."""
        return -STOPPED_REV_S < self.omega < STOPPED_REV_S

    def step(self, dt: float, demand: float | None, lag: float,
             vmax: float = math.inf) -> None:
        """Advance dt seconds following ``demand`` (None: no torque, the motor coasts) at no
        more than ``vmax`` rev/s (d3, the motor's maximum speed)."""
        if self.jammed:
            self.omega = 0.0
            self._last_demand = demand
            return
        if demand is not None:
            follow_demand(self, demand, lag, vmax, dt)
            return
        before = self.theta
        self.omega *= math.exp(-dt / COAST_TIME_CONSTANT_S)
        if abs(self.omega) < STOPPED_REV_S:
            self.omega = 0.0
        new = self.theta + self.omega * dt
        self._last_demand = demand
        low, high = self._end_stops
        self.blocked = blocked = not low <= new <= high
        new = low if low > new else new
        self.theta = theta = high if high < new else new
        if blocked:
            self.omega = (theta - before) / dt if dt > 0.0 else 0.0


def follow_demand(plant: Plant, demand: float, lag: float, vmax: float, dt: float) -> None:
    """One step of the free motor (not jammed) following ``demand``: Plant.step's torque case,
    and what the drive's full tick and cruise tick call straight (devices/servo/ticking.py),
    without the method's jam and coast branches."""
    before = plant.theta
    # exact response of a first-order lag to a demand ramping linearly over the step
    previous = plant._last_demand
    if previous is None:
        previous = demand
    rate = (demand - previous) / dt if dt > 0.0 else 0.0
    decay = _exp(-dt / lag) if lag > 0.0 else 0.0
    new = demand - rate * lag + (before - previous + rate * lag) * decay
    if abs(demand - new) < SETTLED_REV:
        new = demand
    # the speed loop saturates at Vmax: a demand that runs away (electronic axis,
    # interpolator) leaves the motor behind, and the following error grows
    reach = vmax * dt
    if new - before > reach:
        new = before + reach
    elif before - new > reach:
        new = before - reach
    plant._last_demand = demand
    low, high = plant._end_stops
    plant.blocked = not low <= new <= high
    new = low if low > new else new  # min(max(new, low), high), written out (every tick)
    plant.theta = theta = high if high < new else new
    plant.omega = (theta - before) / dt if dt > 0.0 else 0.0
