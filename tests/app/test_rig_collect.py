"""Rig._collect looks into the devices' event queues only after a put (docs/performance.md
"Session 22"), and still hands every event over once, in device order."""

from __future__ import annotations

from app.rig import Rig
from devices.events import EventQueue, LogLine


class _Model:
    """A device that emits the lines it is told to at its next step, and counts the reads of
    its queue from outside."""

    def __init__(self, device_id: str) -> None:
        self.device_id = device_id
        self._events = EventQueue()
        self.reads = 0
        self.now_us = 0
        self.script: dict[int, list[str]] = {}

    @property
    def events(self) -> EventQueue:
        self.reads += 1
        return self._events

    def drain_events(self) -> list:
        return self._events.drain()

    def step(self, now_us: int) -> None:
        self.now_us = now_us
        for text in self.script.pop(now_us, []):
            self._events.put(LogLine(now_us, self.device_id, text=text))


def _rig(name: str, *ids: str) -> Rig:
    return Rig(name, {i: _Model(i) for i in ids})  # type: ignore[misc]


def test_a_step_with_nothing_put_reads_no_queue() -> None:
    rig = _rig("r", "a", "b", "c")
    rig.step()  # the first look
    models = list(rig.devices.values())
    for m in models:
        m.reads = 0
    for _ in range(100):
        assert rig.step() == []
    assert [m.reads for m in models] == [0, 0, 0]  # each step looked at all three before


def test_every_event_once_in_device_order() -> None:
    rig = _rig("r", "a", "b")
    a, b = rig.devices["a"], rig.devices["b"]
    step_us = rig.clock.step_us
    b.script[2 * step_us] = ["b1"]
    a.script[2 * step_us] = ["a1", "a2"]
    a.script[5 * step_us] = ["a3"]
    got = [[e.text for e in rig.step()] for _ in range(6)]
    assert got == [[], ["a1", "a2", "b1"], [], [], ["a3"], []]


def test_a_put_in_another_rig_neither_hides_nor_repeats_an_event() -> None:
    one, two = _rig("one", "a"), _rig("two", "x")
    step_us = one.clock.step_us
    one.devices["a"].script[step_us] = ["mine"]
    two.devices["x"].script[step_us] = ["theirs"]
    assert [e.text for e in two.step()] == ["theirs"]  # the last put is two's
    assert [e.text for e in one.step()] == ["mine"]
    assert one.step() == [] and two.step() == []
    one.devices["a"].script[3 * step_us] = ["again"]
    two.devices["x"].script[3 * step_us] = ["later"]
    assert [e.text for e in one.step()] == ["again"]  # put before two's, seen all the same
    assert [e.text for e in two.step()] == ["later"]


def test_a_queue_made_with_events_is_looked_into() -> None:
    rig = _rig("r", "a")
    rig.step()
    model = rig.devices["a"]
    model._events = EventQueue([LogLine(0, "a", text="made with it")])
    assert [e.text for e in rig.step()] == ["made with it"]
