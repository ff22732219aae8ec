"""The runtime skips a quiet span only when every step listener has nothing due in it.

A listener that says until when it has nothing to do (``quiet_until``) still runs at each of
its due times; one that says nothing keeps the rig stepping one step at a time. Stand-in models
with a known timetable (test_rig_spans.Blinker).
"""

from __future__ import annotations

import random
from collections.abc import Iterator

import pytest
from test_rig_spans import Blinker, Still, rig

from app.rig import Rig
from app.runtime import Runtime

PERIOD_US = 10_000
WAIT_S = 60.0


class Sampler:
    """Takes the rig's snapshot every PERIOD_US, like the recorder and the drive plots."""

    def __init__(self, source: Rig) -> None:
        self.rig = source
        self.next_us = PERIOD_US
        self.samples: list[tuple[int, object]] = []

    def on_step(self, now_us: int) -> None:
        if now_us >= self.next_us:
            self.samples.append((now_us, self.rig.snapshot()))
            self.next_us = now_us - now_us % PERIOD_US + PERIOD_US

    def quiet_until(self, now_us: int, step_us: int) -> int:
        return self.next_us - 1


def blinkers() -> Rig:
    return rig(Blinker("a", random.Random(1)), Blinker("b", random.Random(2)))


@pytest.fixture
def runtimes() -> Iterator[tuple[Runtime, Runtime]]:
    spans, steps = Runtime(blinkers()), Runtime(blinkers())
    steps.rig.SKIP_SPANS = False  # type: ignore[misc]
    for runtime in (spans, steps):
        runtime.set_paused(True)
        runtime.start()
    yield spans, steps
    for runtime in (spans, steps):
        runtime.stop()


def run(runtime: Runtime, listener_span: bool) -> tuple[list[tuple[int, object]], list]:
    sampler = Sampler(runtime.rig)
    runtime.add_step_listener(sampler.on_step,
                              quiet_until=sampler.quiet_until if listener_span else None)
    runtime.advance(1_000_000).result(timeout=WAIT_S)
    return sampler.samples, runtime.events_since(0)[1]


def test_a_listener_with_its_span_sees_every_due_step(runtimes) -> None:
    spans, steps = runtimes
    skipped = run(spans, True)
    assert skipped == run(steps, True)
    assert len(skipped[0]) == 100 and len(skipped[1]) > 200
    assert spans.rig.skipped_steps > 500


def test_a_listener_without_a_span_keeps_every_step(runtimes) -> None:
    spans, _ = runtimes
    run(spans, False)
    assert spans.rig.skipped_steps == 0


def test_a_listener_due_at_a_quiet_step_runs_after_the_skip() -> None:
    """The step a listener is due at is skipped with the span before it when every device is
    quiet through it; the listener then runs as it would after that step (Rig.quiet_span)."""
    runtime = Runtime(rig(Still("a"), Still("b")))
    runtime.set_paused(True)
    runtime.start()
    try:
        stepped: list[int] = []
        step = runtime.rig.step
        runtime.rig.step = lambda: (stepped.append(runtime.rig.clock.now_us), step())[1]
        samples, events = run(runtime, True)
    finally:
        runtime.stop()
    assert [t for t, _ in samples] == list(range(PERIOD_US, 1_000_001, PERIOD_US))
    assert stepped == [] and events == []
    assert runtime.rig.skipped_steps == 1000
