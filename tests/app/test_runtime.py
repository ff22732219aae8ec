"""The runtime: commands cross threads by message and run at step boundaries."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Any, ClassVar

import pytest

from app.clock import SimClock
from app.rig import Rig
from app.runtime import ACTIVE_NAP_S, ACTIVE_S, IDLE_NAP_S, Runtime, nap_s
from devices.device import Action, CommandError, DeviceModel, Param
from devices.events import LogLine


@dataclass
class Counter(DeviceModel):
    """A device that counts its steps and logs on command (test double for the runtime)."""

    steps: int = 0
    thread: str = ""
    ACTIONS: ClassVar[dict[str, Action]] = {
        "say": Action("say", "log a line", (Param("text", str),)),
    }

    def step(self, now_us: int) -> None:
        super().step(now_us)
        self.steps += 1
        self.thread = threading.current_thread().name

    def snapshot(self) -> dict[str, Any]:
        return {"steps": self.steps}

    def cmd_say(self, text: str) -> str:
        self.emit(LogLine(self.now_us, self.device_id, text=text))
        return text.upper()


@pytest.fixture
def runtime():
    rig = Rig("t", {"c": Counter("c")}, SimClock(step_us=1000))
    rt = Runtime(rig, speed=20.0, publish_hz=200)
    rt.start()
    yield rt
    rt.stop()


def test_command_runs_in_simulation_thread_and_returns(runtime: Runtime) -> None:
    assert runtime.command("c", "say", {"text": "hi"}).result(timeout=5) == "HI"
    assert runtime.rig.devices["c"].thread == "fieldrig-sim"


def test_command_error_reaches_caller_and_simulation_goes_on(runtime: Runtime) -> None:
    with pytest.raises(CommandError, match="no action 'jump'"):
        runtime.command("c", "jump").result(timeout=5)
    with pytest.raises(CommandError, match="no device 'x'"):
        runtime.command("x", "say", {"text": "a"}).result(timeout=5)
    before = runtime.submit(lambda: runtime.rig.clock.now_us).result(timeout=5)
    deadline = time.monotonic() + 5
    while runtime.submit(lambda: runtime.rig.clock.now_us).result(timeout=5) <= before:
        assert time.monotonic() < deadline, "simulation stopped after a bad command"


def test_events_are_journalled_in_order(runtime: Runtime) -> None:
    seq0, _ = runtime.events_since(0)
    for word in ("a", "b", "c"):
        runtime.command("c", "say", {"text": word})
    runtime.submit(lambda: None).result(timeout=5)
    deadline = time.monotonic() + 5
    texts: list[str] = []
    while len(texts) < 3 and time.monotonic() < deadline:
        _, events = runtime.events_since(seq0)
        texts = [e.text for e in events if isinstance(e, LogLine)]
    assert texts == ["a", "b", "c"]


def test_frames_advance_and_pause_freezes_time(runtime: Runtime) -> None:
    deadline = time.monotonic() + 5
    while runtime.frame.snapshot["devices"]["c"]["steps"] == 0:
        assert time.monotonic() < deadline
    runtime.set_paused(True)
    frozen = runtime.submit(lambda: runtime.rig.clock.now_us).result(timeout=5)
    time.sleep(0.05)
    assert runtime.submit(lambda: runtime.rig.clock.now_us).result(timeout=5) == frozen
    runtime.set_paused(False)


def test_speed_is_checked(runtime: Runtime) -> None:
    with pytest.raises(ValueError):
        runtime.set_speed(0)


def test_lowering_the_speed_does_not_freeze_the_clock(runtime: Runtime) -> None:
    """A new speed counts from the moment it is set (a slower clock must not wait for wall
    time to catch up with the faster past)."""
    time.sleep(0.3)  # 6 simulated seconds at 20x
    runtime.set_speed(1.0)
    start = runtime.submit(lambda: runtime.rig.clock.now_us).result(timeout=5)
    time.sleep(0.3)
    later = runtime.submit(lambda: runtime.rig.clock.now_us).result(timeout=5)
    assert later - start >= 100_000


def test_a_speed_beyond_the_cpu_still_runs_flat_out() -> None:
    """Asking more than the CPU gives must not stall the clock (the catch-up slips instead)."""
    rig = Rig("t", {"c": Counter("c")}, SimClock(step_us=1000))
    rt = Runtime(rig, speed=1000.0)
    rt.start()
    try:
        time.sleep(0.5)
        advanced = rt.submit(lambda: rig.clock.now_us).result(timeout=5)
    finally:
        rt.stop()
    assert advanced >= 1_000_000  # a counter steps far faster than 2x real time


@dataclass
class Busy(DeviceModel):
    """A device whose step lets other threads run in the middle of it (time.sleep(0) gives up
    the GIL), so a caller that did not wait for the step would see ``inside`` set."""

    inside: bool = False

    def step(self, now_us: int) -> None:
        super().step(now_us)
        self.inside = True
        time.sleep(0)
        self.inside = False

    def snapshot(self) -> dict[str, Any]:
        return {}


def test_call_runs_between_two_steps_in_the_callers_thread() -> None:
    """Runtime.call (the Modbus line's way in, benchmark 4): the function runs in the calling
    thread, never while the simulation thread is inside a step, and its events are journalled
    in the order they came."""
    busy, counter = Busy("b"), Counter("c")
    rt = Runtime(Rig("t", {"b": busy, "c": counter}, SimClock(step_us=1000)), speed=50.0)
    rt.start()
    try:
        seen: list[bool] = []
        threads: set[str] = set()
        deadline = time.monotonic() + 10
        # Calls back to back: the simulation must still get its steps (the lock is not fair;
        # call() lets a waiting simulation thread go first). Counted from the first call, and
        # at least 20 calls: at speed 50 the 200 steps take 4 ms, which a loaded machine can
        # spend before this thread's first call (a CI run saw no call at all).
        start = rt.call(lambda: counter.steps)
        while rt.call(lambda: counter.steps) < start + 200 or len(seen) < 20:
            assert time.monotonic() < deadline, "the simulation starved"
            seen.append(rt.call(lambda: busy.inside))
            threads.add(rt.call(lambda: threading.current_thread().name))
        assert not any(seen)
        assert threads == {threading.current_thread().name}
        seq0, _ = rt.events_since(0)
        for word in ("x", "y"):
            assert rt.call(lambda w=word: rt.rig.apply("c", "say", {"text": w})) == word.upper()
        _, events = rt.events_since(seq0)  # journalled by call itself, no step needed
        assert [e.text for e in events if isinstance(e, LogLine)] == ["x", "y"]
        assert rt.call(lambda: rt.call(lambda: 7)) == 7  # a call inside a call goes through
    finally:
        rt.stop()


def test_call_journals_what_a_failing_function_emitted(runtime: Runtime) -> None:
    runtime.set_paused(True)  # no step will collect the event: call must journal it itself
    runtime.submit(lambda: None).result(timeout=5)
    seq0, _ = runtime.events_since(0)

    def say_then_fail() -> None:
        runtime.rig.apply("c", "say", {"text": "before"})
        raise RuntimeError("after")

    with pytest.raises(RuntimeError, match="after"):
        runtime.call(say_then_fail)
    _, events = runtime.events_since(seq0)  # at once, not at the next step
    assert [e.text for e in events if isinstance(e, LogLine)] == ["before"]


def test_nap_is_short_while_something_talks_to_the_rig() -> None:
    now = 100.0
    # work within ACTIVE_S, or a real-time step listener: a step within about a millisecond
    assert nap_s(now, now - ACTIVE_S / 2, now + 1.0, realtime=False) == ACTIVE_NAP_S
    assert nap_s(now, now - 60.0, now + 1.0, realtime=True) == ACTIVE_NAP_S
    # idle: steps in batches, but no later than the next publication
    assert nap_s(now, now - 60.0, now + 1.0, realtime=False) == IDLE_NAP_S
    assert nap_s(now, now - 60.0, now + 0.004, realtime=False) == pytest.approx(0.004)
    assert nap_s(now, now - 60.0, now - 0.5, realtime=False) == ACTIVE_NAP_S


def test_a_call_keeps_the_simulation_on_short_naps(monkeypatch: pytest.MonkeyPatch) -> None:
    """A protocol server's request (call) talks to the rig as queued work does: the thread
    then steps every millisecond, so the next reads see the rig within a step of wall time
    (on idle 10 ms naps a Modbus poll of a moving axis read it up to 10 ms behind)."""
    import app.runtime as runtime_module

    naps: list[tuple[float, float]] = []  # (now, last_work) of each nap taken

    def recorded(now: float, last_work: float, next_publish: float, realtime: bool) -> float:
        naps.append((now, last_work))
        return nap_s(now, last_work, next_publish, realtime)

    monkeypatch.setattr(runtime_module, "nap_s", recorded)
    rig = Rig("t", {"c": Counter("c")}, SimClock(step_us=1000))
    runtime = Runtime(rig)
    runtime.start()
    try:
        time.sleep(ACTIVE_S + 0.3)  # idle: naps of IDLE_NAP_S
        called = time.monotonic()
        runtime.call(lambda: rig.clock.now_us)
        deadline = called + 10
        while not any(now > called for now, _ in naps):
            assert time.monotonic() < deadline, "the simulation thread took no nap"
            time.sleep(0.005)
        now, last_work = next((n, w) for n, w in naps if n > called)
        assert now - last_work <= ACTIVE_S  # the call counted as work: short naps follow
    finally:
        runtime.stop()


def test_idle_runtime_keeps_real_time_and_answers_at_once() -> None:
    """Stepping in idle batches changes neither the simulated time's pace nor how soon queued
    work runs."""
    rig = Rig("t", {"c": Counter("c")}, SimClock(step_us=1000))
    runtime = Runtime(rig)
    runtime.start()
    try:
        time.sleep(1.2)  # well past ACTIVE_S: idle naps
        wall0, sim0 = time.monotonic(), rig.clock.now_us
        time.sleep(0.5)
        started = time.monotonic()
        t_us = runtime.submit(lambda: rig.clock.now_us).result(timeout=5)
        answered = time.monotonic() - started
        ran = (t_us - sim0) / 1e6
        assert ran == pytest.approx(time.monotonic() - wall0, abs=0.15)
        assert answered < 0.25  # queued work wakes the thread (not after an idle nap)
    finally:
        runtime.stop()


def test_work_that_pauses_and_resets_the_clock_stops_the_running_batch() -> None:
    """A scenario load on a running rig (app/player.py) pauses, then resets the clock to 0 in
    the simulation thread. Taken between two steps of a running batch, the batch went on up to
    its target, the old clock's time: the review saw "finished · t = 0.0 s of 16 s" a few
    seconds after Play and then "t = 756.8 s of 16 s" (the whole scenario and 12 minutes more
    run at CPU speed on the fresh rig). The batch stops once such work ran."""
    rig = Rig("t", {"c": Counter("c")}, SimClock(step_us=1000))
    rt = Runtime(rig, speed=1000.0)
    loaded = threading.Event()

    def reset() -> None:  # as app.player.reset_in_place: a fresh device, the clock at 0
        rig.devices["c"].__dict__ = Counter("c").__dict__
        rig.clock.now_us = 0
        rt.set_speed(rt.speed)  # as Player.load: the wall clock rebased on time 0
        loaded.set()

    def on_step(now_us: int) -> None:  # in the batch: the work is taken after this step
        if now_us >= 50_000 and not loaded.is_set() and not rt.paused:
            rt.set_paused(True)
            rt.submit(reset)

    rt.add_step_listener(on_step)
    rt.start()
    try:
        assert loaded.wait(timeout=5)
        time.sleep(0.2)
        after = rt.submit(lambda: rig.clock.now_us).result(timeout=5)
    finally:
        rt.stop()
    assert after == 0, f"the paused clock ran on to {after / 1e6:.3f} s after the reset"
