"""Quiet spans of the CPX-E-EC are exact (docs/cpx-e-ec.md "Quiet spans").

A rig skips a span of steps when every model says its steps would be quiet
(``CpxEEc.quiet_until`` / ``skip_to``); an EtherCAT master passes the frames of the span in one
go (``frames_quiet`` / ``skip_frames``). Exact or wrong: a skipping rig and a plain one, the
same commands, must give the same events and the same deep state (span_runs.differential).

- the CPX-E-EC alone, no master: powered off, INIT / PREOP / SAFEOP / OP reached by AL
  requests, with "no master", the SM watchdog, LA IN and the 20 ms bridging running out on
  the clock, diagnoses latched, faults injected and cleared, inputs, outputs, supplies,
  cables, switches, object writes, power cycles;
- the same with a stand-in master (:class:`FrameSource`) that passes a frame every cycle and
  takes the emergencies, and skips the frames of a quiet span with ``skip_frames`` as the
  master is to: OP with the frames arriving (the default rig's idle state), the frames
  stopping and starting, a sync error's counter at its cap, the watchdog fault;
- ``frames_quiet`` / ``skip_frames`` directly: n frames interleaved with steps against
  ``skip_to`` + ``skip_frames``, the default rig's CPX-E-EC among them.

Each asserts that steps were skipped, so a span switched off by mistake fails it.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from typing import Any

import pytest
from span_runs import deep_state, differential
from test_still_cpx import random_fault

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec, parse_rig_spec
from devices.cpx.device import ACTIVITY_WINDOW_US, CpxEEc
from devices.cpx.transitions import WATCHDOG_US
from devices.device import DeviceModel
from devices.ethercat import AlState

Op = tuple[str, str, dict[str, Any]]
STEP_US = 1000

CPX_ALONE = """
[rig]
name = "CPX-E-EC alone"
seed = 7
step_ms = 1

[[cpx]]
id = "cpx"
rotary_switch = 0
dil2 = true
history_flags = 1
modules = ["CPX-E-16DI", "CPX-E-8DO", "CPX-E-4AI-U-I", "CPX-E-4AO-U-I", "CPX-E-1CI"]
"""


class FrameSource(DeviceModel):
    """The master's part a slave sees, for the tests: while ``sending``, every ``cycle_us``
    a frame (``exchange_frame``) and the mailbox emptied (``take_emergencies``) for each
    reachable slave, after the slaves' steps (it steps last). Its quiet span: unbounded while
    it sends nothing, or while every reachable slave's ``frames_quiet`` holds; ``skip_to``
    passes the span's frames with ``skip_frames`` after the slaves' own ``skip_to``."""

    KIND = "test_frames"

    def __init__(self, slaves: list[CpxEEc], cycle_us: int, step_us: int) -> None:
        super().__init__(device_id="frames", rng=random.Random(0))
        self.slaves, self.cycle_us, self.step_us = slaves, cycle_us, step_us
        self.sending = False
        self.next_us = 0
        self.frames = 0
        self.emergencies = 0

    def step(self, now_us: int) -> None:
        super().step(now_us)
        if self.sending and now_us >= self.next_us:
            self.next_us = now_us + self.cycle_us
            self.frames += 1
            for slave in self.slaves:
                if slave.reachable():
                    slave.exchange_frame(now_us)
                    self.emergencies += len(slave.take_emergencies())

    def quiet_until(self, step_us: int) -> int:
        if self.sending and not all(s.frames_quiet() for s in self.slaves if s.reachable()):
            return self.now_us
        return self.now_us + 10**9 * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        if self.sending:
            first = max(self.next_us, self.now_us + self.step_us)
            if first <= t_us:
                n = (t_us - first) // self.cycle_us + 1
                last = first + (n - 1) * self.cycle_us
                for slave in self.slaves:
                    if slave.reachable():
                        slave.skip_frames(n, last)
                self.next_us, self.frames = last + self.cycle_us, self.frames + n
        self.now_us = t_us

    def snapshot(self) -> dict[str, Any]:
        return {"kind": self.KIND, "sending": self.sending, "frames": self.frames,
                "emergencies": self.emergencies}


class CpxRig(Rig):
    """A rig of one CPX-E-EC (and maybe a FrameSource) whose ``apply`` also takes what a
    master or the wire's face would do: AL requests, frames on / off, face writes."""

    def apply(self, target: str, action: str, args: dict[str, Any]) -> Any:
        model = self.devices["cpx"]
        assert isinstance(model, CpxEEc)
        source = self.devices.get("frames")
        if action == "request_state":
            model.request_state(AlState[args["state"]])
        elif action == "bring_up":  # a master's start: a frame, then INIT -> ... -> OP
            if isinstance(source, FrameSource):
                source.sending = True
            model.exchange_frame(self.clock.now_us)
            for state in ("INIT", "PREOP", "SAFEOP", "OP"):  # acknowledging a flag (bit 4)
                model.request_state(AlState[state], ack=bool(model.al_status & 0x10))
        elif action == "heal":  # back to a CPX-E-EC that can run in OP, then brought up
            for op in HEAL:
                super().apply(*op)
            return self.apply(target, "bring_up", {})
        elif action == "send":
            assert isinstance(source, FrameSource)
            source.sending = args["on"]
        elif action == "face_write":
            model.cmd_write_object(args["index"], args["sub"], args["value"])
        else:
            return super().apply(target, action, args)
        self._collect()
        return None


# Most operations should find the CPX-E-EC in OP (where the spans save most and have most to
# miss): a quarter of them bring it back there.
HEAL: tuple[Op, ...] = (
    ("cpx", "power", {"on": True}), ("cpx", "supply", {"el_sen": 24.0, "out": 24.0}),
    ("cpx", "cable", {"port": "in", "connected": True}),
    ("cpx/5", "set_count_rate", {"hz": 0.0}),
    *(("cpx", "clear_fault", {"fault": f})
      for f in ("ac_failure", "watchdog", "sync_error", "booting_error")),
)


def build(frames_cycle_us: int | None = None) -> CpxRig:
    """The CPX-E-EC of CPX_ALONE, powered; with a FrameSource when a cycle is given."""
    built = build_rig(parse_rig_spec(CPX_ALONE, "<cpx alone>"))
    cpx = built.devices["cpx"]
    assert isinstance(cpx, CpxEEc)
    devices: dict[str, DeviceModel] = {"cpx": cpx}  # no master: build_rig's is left out
    if frames_cycle_us is not None:
        devices["frames"] = FrameSource([cpx], frames_cycle_us, built.clock.step_us)
    return CpxRig(name=built.name, devices=devices, clock=built.clock, seed=built.seed)


OBJECT_WRITES = (  # (index, sub, values) of CPX_ALONE's CPX-E-EC (Tab. 27)
    (0x7002, 1, (0, 1)), (0x7002, 4, (0, 1)), (0x7004, 1, (0, 8000, 32767)),
    (0x2003, 1, (1, 2, 5, 6)), (0x2004, 2, (1, 5, 6)), (0x2400, 2, (0, 1)),
    (0x2400, 3, (0, 1)), (0x2400, 4, (0, 1)), (0x2400, 7, (0, 1, 2)), (0x2401, 0, (0, 1)),
    (0x10F3, 5, (0, 1, 3)), (0x10F3, 3, (0, 6, 7)), (0xF030, 0, (0, 5)),
)
STATES = ("INIT", "PREOP", "SAFEOP", "OP", "OP")


def random_op(rng: random.Random, frames: bool) -> Op:
    module = rng.randint(1, 4)
    fault_target, fault_args = random_fault(rng, module)
    index, sub, values = rng.choice(OBJECT_WRITES)
    choices: list[Callable[[], Op]] = [
        lambda: ("cpx", "bring_up", {}),
        lambda: ("cpx", "bring_up", {}),
        lambda: ("cpx", "request_state", {"state": rng.choice(STATES)}),
        lambda: ("cpx/1", "set_input", {"channel": rng.randint(0, 15), "on": rng.random() < 0.5}),
        lambda: ("cpx/3", "set_analog", {"channel": rng.randint(0, 3),
                                         "value": rng.choice((0.0, 1.0, 4.0, 12.5, 25.0))}),
        lambda: ("cpx/5", "set_count_rate", {"hz": rng.choice((0.0, 0.0, 150.0))}),
        lambda: (f"cpx/{module}", "short_circuit", {"on": rng.random() < 0.6,
                                                    "channel": rng.randint(0, 3)}),
        lambda: (f"cpx/{module}", "wire_break", {"channel": rng.randint(0, 3),
                                                 "on": rng.random() < 0.6}),
        lambda: (f"cpx/{module}", "force", {"channel": rng.randint(0, 7),
                                            **({"value": rng.randint(0, 1)}
                                               if rng.random() < 0.6 else {})}),
        lambda: (fault_target, "inject_fault", fault_args),
        lambda: (fault_target, "clear_fault", fault_args),
        lambda: (fault_target, "clear_fault", fault_args),
        lambda: ("cpx", "write_object", {"index": index, "sub": sub,
                                         "value": rng.choice(values)}),
        lambda: ("cpx", "face_write", {"index": 0x7002, "sub": rng.randint(1, 8),
                                       "value": int(rng.random() < 0.7)}),
        lambda: ("cpx", "read_object", {"index": 0x10F3, "sub": rng.choice((2, 4, 6, 7))}),
        lambda: ("cpx", "power", {"on": rng.random() < 0.7}),
        lambda: ("cpx", "supply", {"el_sen": rng.choice((24.0, 24.0, 17.0, 5.0)),
                                   "out": rng.choice((24.0, 24.0, 12.0, 0.0))}),
        lambda: ("cpx", "cable", {"port": rng.choice(("in", "out")),
                                  "connected": rng.random() < 0.7}),
        lambda: ("cpx", "set_dil", {"dil1": rng.random() < 0.3, "dil2": rng.random() < 0.7}),
        lambda: ("cpx", "restart", {}),
    ]
    if frames:
        choices += [lambda: ("frames", "send", {"on": rng.random() < 0.7})] * 2
    if rng.random() < 0.25:
        return ("cpx", "heal", {})
    return rng.choice(choices)()


@pytest.mark.parametrize("seed", [1, 2, pytest.param(3, marks=pytest.mark.full)])
def test_cpx_alone_skips_exactly(seed: int, full: bool) -> None:
    """No master: the clock runs out "no master", the watchdog, LA IN and the bridging."""
    skipped = differential(build, lambda rng: random_op(rng, False), seed,
                           rounds=400 if full else 35)
    assert skipped > (50_000 if full else 5_000)


@pytest.mark.parametrize(("seed", "cycle_us"), [
    (11, 1000), (12, 2000), pytest.param(13, 1000, marks=pytest.mark.full),
    pytest.param(14, 3000, marks=pytest.mark.full)])
def test_cpx_with_frames_skips_exactly(seed: int, cycle_us: int, full: bool) -> None:
    """A stand-in master's frames every cycle, passed in one go over a quiet span."""
    skipped = differential(lambda: build(cycle_us), lambda rng: random_op(rng, True), seed,
                           rounds=400 if full else 35)
    assert skipped > (50_000 if full else 5_000)


# ---- frames_quiet / skip_frames directly ----------------------------------------------------
def settle(rig: Rig, ops: list[Op], steps: int = 400) -> CpxEEc:
    for op in ops:
        rig.apply(*op)
    rig.advance(steps)
    model = rig.devices["cpx"]
    assert isinstance(model, CpxEEc)
    return model


def frames_against_skip(make: Callable[[], tuple[Rig, CpxEEc]], spans: int) -> int:
    """``spans`` quiet spans: one model stepped with a frame after each step (one per ms, as
    the master does), its twin skipped with skip_to + skip_frames; the steps compared."""
    (rig_a, a), (rig_b, b) = make(), make()
    rig_a.SKIP_SPANS = rig_b.SKIP_SPANS = False  # type: ignore[misc]
    assert deep_state(a) == deep_state(b)
    total = 0
    for _ in range(spans):
        now = a.now_us
        until = a.quiet_until(STEP_US)
        assert until == b.quiet_until(STEP_US) and a.frames_quiet() and b.frames_quiet()
        n = (until - now) // STEP_US
        assert n >= 2
        for k in range(1, n + 1):
            a.step(now + k * STEP_US)
            a.exchange_frame(now + k * STEP_US)
            assert not a.take_emergencies()
        b.skip_to(until, STEP_US)
        b.skip_frames(n, until)
        assert not a.drain_events() and not b.drain_events()
        assert deep_state(a) == deep_state(b)
        assert a.snapshot() == b.snapshot()
        rig_a.clock.now_us = rig_b.clock.now_us = until
        total += n
    return total


CASES: dict[str, list[Op]] = {
    "OP": [("cpx", "bring_up", {})],
    "OP, a latched diagnosis": [("cpx", "bring_up", {}),
                                ("cpx/3", "set_analog", {"channel": 1, "value": 1.0}),
                                ("cpx", "write_object", {"index": 0x2003, "sub": 2, "value": 6}),
                                ("cpx/2", "short_circuit", {"on": True, "channel": 1})],
    "SAFEOP, sync error at the cap": [("cpx", "bring_up", {}),
                                      ("cpx", "inject_fault", {"fault": "sync_error"})],
    "OP, sync counter going down": [("cpx", "bring_up", {}),
                                    ("cpx", "inject_fault", {"fault": "sync_error"})],
    "SAFEOP, watchdog fault": [("cpx", "bring_up", {}),
                               ("cpx", "inject_fault", {"fault": "watchdog"})],
    "PREOP": [("cpx", "bring_up", {}), ("cpx", "request_state", {"state": "PREOP"})],
}


@pytest.mark.parametrize("case", list(CASES))
def test_frames_against_skip_frames(case: str) -> None:
    def make() -> tuple[Rig, CpxEEc]:
        rig = build(STEP_US)
        going_down = case == "OP, sync counter going down"
        model = settle(rig, CASES[case], 4 if going_down else 400)
        if going_down:  # OP -> SAFEOP, the counter at its cap (7); cleared, back in OP
            model.apply("clear_fault", {"fault": "sync_error"})
            rig.advance(4)  # 7 -> 3: under the limit (4), OP may be entered again
            model.request_state(AlState.OP, ack=True)  # AL control bit 4 over the fall's flag
            rig.advance(2)  # 3 -> 1, the still step proved: the span's frames count it down
            assert model.esm.state is AlState.OP and model.sync_counter == 1
        return rig, model
    total = frames_against_skip(make, 4)
    assert total >= 8


def test_the_default_rigs_cpx_idle_in_op() -> None:
    """The default rig's CPX-E-EC, in OP with the master's frames every 1 ms: a 50 ms span
    (LA IN's activity window, from the last frame), frames quiet; and the same frames
    against skip_frames on two such rigs."""
    def make() -> tuple[Rig, CpxEEc]:
        rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
        for _ in range(3000):
            rig.step()
        model = rig.devices["cpx"]
        assert isinstance(model, CpxEEc) and model.esm.state is AlState.OP
        return rig, model
    assert ACTIVITY_WINDOW_US < WATCHDOG_US  # quiet_until: traffic's end comes first
    _, model = make()
    assert model.last_frame_us == model.now_us
    assert model.quiet_until(STEP_US) == model.now_us + 50 * STEP_US
    assert model.frames_quiet()
    assert frames_against_skip(make, 3) == 150


def test_no_span_when_not_still() -> None:
    """Touched, a counting module, a different step length: no span."""
    rig = build(STEP_US)
    model = settle(rig, [("cpx", "bring_up", {})])
    assert model.quiet_until(STEP_US) > model.now_us
    assert model.quiet_until(2 * STEP_US) == model.now_us
    model.apply("set_input", {"channel": 0, "on": True}, 1)
    assert model.quiet_until(STEP_US) == model.now_us
    rig.apply("cpx/5", "set_count_rate", {"hz": 150.0})
    rig.advance(500)
    assert model.quiet_until(STEP_US) == model.now_us
