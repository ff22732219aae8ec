"""Rig.advance skips spans in which every device is quiet, and only those (app/rig.py).

Models here are small stand-ins with a known timetable: a blinker that toggles every 7 steps
(quiet in between, its skip_to moving a counter and its rng as the steps would) and a model
without quiet steps (the DeviceModel default). The real models' spans are tested against
stepping in tests/hardening/test_spans_*.py.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Any

import pytest

from app.clock import SimClock
from app.rig import MIN_SPAN, Rig
from devices.device import DeviceModel
from devices.events import StateChanged

PERIOD = 7


@dataclass
class Blinker(DeviceModel):
    """Toggles every PERIOD steps; counts steps and draws once a step in between."""

    lit: bool = False
    steps: int = 0
    asked: int = field(default=0, compare=False)

    def step(self, now_us: int) -> None:
        super().step(now_us)
        self.steps += 1
        self.rng.random()
        if self.steps % PERIOD == 0:
            self.lit = not self.lit
            self.emit(StateChanged(now_us, self.device_id, from_state=str(not self.lit),
                                   to_state=str(self.lit), machine="blink"))

    def quiet_until(self, step_us: int) -> int:
        self.asked += 1
        left = PERIOD - 1 - self.steps % PERIOD  # steps before the next toggle
        return self.now_us + left * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        n = (t_us - self.now_us) // step_us
        for _ in range(n):
            self.rng.random()
        self.steps += n
        self.now_us = t_us

    def snapshot(self) -> dict[str, Any]:
        return {"lit": self.lit, "steps": self.steps, "rng": self.rng.getstate()}


@dataclass
class Still(DeviceModel):
    """Nothing ever changes: every step is quiet."""

    def quiet_until(self, step_us: int) -> int:
        return self.now_us + 1_000_000 * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        self.now_us = t_us

    def snapshot(self) -> dict[str, Any]:
        return {"now_us": self.now_us}


@dataclass
class Busy(DeviceModel):
    """No quiet steps (the default)."""

    steps: int = 0

    def step(self, now_us: int) -> None:
        super().step(now_us)
        self.steps += 1

    def snapshot(self) -> dict[str, Any]:
        return {"steps": self.steps}


def rig(*devices: DeviceModel, step_us: int = 1000) -> Rig:
    return Rig("spans", {d.device_id: d for d in devices}, SimClock(step_us=step_us))


def blinkers() -> Rig:
    return rig(Blinker("a", random.Random(1)), Blinker("b", random.Random(2)))


@pytest.mark.parametrize("steps", [0, 1, MIN_SPAN, 6, 7, 8, 50, 1001])
def test_advance_gives_what_stepping_gives(steps: int) -> None:
    skipping, stepping = blinkers(), blinkers()
    stepping.SKIP_SPANS = False  # type: ignore[misc]
    assert skipping.advance(steps) == [e for _ in range(steps) for e in stepping.step()]
    assert skipping.snapshot() == stepping.snapshot()
    assert skipping.clock.now_us == steps * 1000
    if steps >= 50:
        assert skipping.skipped_steps > steps // 2


def test_the_spans_end_where_the_first_device_stops_being_quiet() -> None:
    a, b = Blinker("a", random.Random(1)), Blinker("b", random.Random(2))
    b.steps = 3  # b toggles 3 steps before a does
    r = rig(a, b)
    events = r.advance(20)
    assert [(e.device, e.t_us) for e in events] == [
        ("b", 4000), ("a", 7000), ("b", 11000), ("a", 14000), ("b", 18000)]


def test_a_device_without_quiet_steps_keeps_the_rig_stepping() -> None:
    r = rig(Blinker("a", random.Random(1)), Busy("busy"))
    r.advance(500)
    assert r.skipped_steps == 0 and r.devices["busy"].snapshot() == {"steps": 500}


def test_run_until_stops_at_the_last_step_not_past_the_time() -> None:
    r = blinkers()
    r.run_until(12_345)
    assert r.clock.now_us == 12_000
    r.run_until(11_000)  # the past: nothing to do
    assert r.clock.now_us == 12_000


def test_a_failed_ask_is_not_repeated_every_step() -> None:
    """After a "no" the rig waits 1, 2, 4 .. steps before asking again (stillness.Backoff)."""
    busy_first = rig(Busy("busy"), Blinker("a", random.Random(1)))
    busy_first.advance(1000)
    asked = busy_first.devices["a"].asked
    assert asked == 0  # the busy device answers first and ends every ask
    r = rig(Blinker("a", random.Random(1)), Busy("busy"))
    r.advance(1000)
    assert r.devices["a"].asked < 30
