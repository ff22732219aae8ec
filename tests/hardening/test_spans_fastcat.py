"""Quiet spans of the FastCAT coupler (docs/fastcat-coupler.md "Quiet spans").

A rig that skips the coupler's quiet spans (``Rig.advance``) against one stepping every step,
compared after every op and stretch (tests/hardening/span_runs.py): events, snapshots and the
deep state of every model, rng states included. The rigs hold one coupler (build_rig's master
taken off) and, in the second
family of runs, a stand-in for the master (:class:`Feeder`) that passes the coupler a frame and
reads its mailbox every cycle and drives its AL state, and that skips its frames in a span as
the built-in master will (``frames_quiet`` / ``skip_frames``). The slave side alone: two
couplers in the same quiet state, one given a frame per millisecond between its steps, the
other skipped (``skip_to`` + ``skip_frames``), must end with the same deep state.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import pytest

from app.rig import Rig
from app.rig_config import build_rig, parse_rig_spec
from devices.device import Action, DeviceModel, Param
from devices.ethercat import AlState
from devices.fastcat.coupler import ACTIVITY_WINDOW_US, FastCat
from devices.fastcat.esm import SM_WATCHDOG_US
from devices.flash import MemoryFlash
from tests.hardening.span_runs import (
    Op,
    advance_alike,
    deep_state,
    differential,
    lines,
    plain,
    rig_state,
)

STEP_US = 1_000
MODULES = ("DB16", "DI16", "DO16", "AI8D", "AO4", "AI8TC", "AX2")  # static/rigs/default.toml
RIG = """
[rig]
name = "fastcat spans"
seed = {seed}
step_ms = 1

[[fastcat]]
id = "fc"
flash = ":memory:"
modules = {modules}
"""
FOREVER = 1 << 30  # an unpowered coupler's span reaches past any stretch


class Feeder(DeviceModel):
    """The master's part a coupler sees: a frame and a mailbox read every ``cycle`` steps,
    AL control on command. Its span: none if the coupler says its frames are not quiet."""

    KIND = "feeder"
    ACTIONS: ClassVar[Mapping[str, Action]] = {a.name: a for a in (
        Action("send", "frames on or off, one every cycle_ms",
               (Param("on", bool), Param("cycle_ms", int, False, 1, low=1, high=80))),
        Action("request", "AL control", (Param("state", str, choices=(
            "INIT", "PREOP", "SAFEOP", "OP", "BOOT")),)),
    )}

    def __init__(self, device_id: str, slave: FastCat) -> None:
        super().__init__(device_id=device_id, rng=random.Random(0))
        self.slave = slave
        self.sending = False
        self.cycle_us = STEP_US
        self.frames = 0
        self.emergencies: list[bytes] = []

    def cmd_send(self, on: bool, cycle_ms: int) -> None:
        self.sending, self.cycle_us = on, cycle_ms * STEP_US

    def cmd_request(self, state: str) -> None:
        self.slave.request_state(AlState[state])

    def step(self, now_us: int) -> None:
        super().step(now_us)
        if self.sending and now_us % self.cycle_us == 0:
            self.slave.exchange_frame(now_us)
            self.frames += 1
            self.emergencies += self.slave.take_emergencies()

    def quiet_until(self, step_us: int) -> int:
        if self.sending and not self.slave.frames_quiet():
            return self.now_us
        return self.now_us + FOREVER * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        n = t_us // self.cycle_us - self.now_us // self.cycle_us if self.sending else 0
        self.now_us = t_us
        if n:  # after the slave's own skip_to, as the master will
            self.frames += n
            self.slave.skip_frames(n, t_us - t_us % self.cycle_us)

    def snapshot(self) -> dict[str, Any]:
        return {"frames": self.frames, "emergencies": [e.hex() for e in self.emergencies]}


def build(seed: int, feeder: bool, modules: tuple[str, ...] = MODULES) -> Rig:
    rig = build_rig(parse_rig_spec(RIG.format(seed=seed, modules=list(modules))))
    # build_rig puts a master on every EtherCAT line; the coupler alone here (no frames), or
    # with the stand-in, which skips its frames in a span as the built-in master will.
    del rig.devices["master"]
    if feeder:
        fc = rig.devices["fc"]
        assert isinstance(fc, FastCat)
        rig.devices["feeder"] = Feeder("feeder", fc)
    return rig


FAULTS = (("fc", "MISSING_NODE_ANSWER"), ("fc", "LINK_LOSS"), ("fc/2", "TARATURA"),
          ("fc/3", "IOFAULT"), ("fc/6", "LOW_VOLTAGE"))


KINDS = {"power": 2, "cnf": 1, "fault": 2, "reset": 2, "write": 2, "rotary": 1, "unplug": 0.4,
         "plug": 2, "swap": 0.2, "module_power": 1, "tbus": 1, "link": 1, "input": 1,
         "analog": 1, "shaft": 1, "short": 1, "failure": 1}
FEEDER_KINDS = {**KINDS, "send": 4, "request": 3}


def op(rng: random.Random, feeder: bool) -> Op:
    """One random command of the family, weighted so that the coupler is often back in a
    quiet state (a module put back, a failure repaired) and a third of them a mere read."""
    if rng.random() < 0.3:
        return ("fc", "read_object", {"index": 0x5100, "sub": 1})  # a read: no touch
    kinds = FEEDER_KINDS if feeder else KINDS
    kind = rng.choices(list(kinds), list(kinds.values()))[0]
    on = rng.random() < 0.5
    slot = rng.randint(1, len(MODULES))
    if kind == "power":
        return ("fc", "power", {"on": rng.random() < 0.7})
    if kind == "cnf":
        return rng.choice((("fc", "press_cnf", {}), ("fc", "release_cnf", {}),
                           ("fc", "hold_cnf", {"seconds": rng.choice((0.2, 3.1))})))
    if kind == "fault":
        target, fault = rng.choice(FAULTS)
        return (target, "inject_fault" if rng.random() < 0.4 else "clear_fault",
                {"fault": fault})
    if kind == "reset":
        return ("fc", "set_reset_fault", {"on": on})
    if kind == "write":
        index, sub, value = rng.choice(((0x7020, rng.randint(1, 16), rng.randint(0, 1)),
                                        (0x7040, rng.randint(1, 4), rng.choice((0, 800))),
                                        (0x5301, 0, rng.randint(0, 1)),
                                        (0x5200, 1, rng.randint(0, 1))))
        return ("fc", "write_object", {"index": index, "sub": sub, "value": value})
    if kind == "rotary":
        return ("fc", "set_rotary", {"value": rng.choice((1, 2))})
    if kind == "unplug":
        return (f"fc/{slot}", "unplug", {})
    if kind == "plug":
        return (f"fc/{slot}", "plug", {"type": MODULES[slot - 1]})
    if kind == "swap":
        return (f"fc/{slot}", "swap", {"other": rng.randint(1, len(MODULES))})
    if kind == "module_power":
        return (f"fc/{slot}", "module_power", {"on": rng.random() < 0.7})
    if kind == "tbus":
        return ("fc", "tbus_voltage", {"low": rng.random() < 0.3})
    if kind == "link":
        return ("fc", "link", {"connected": rng.random() < 0.7})
    if kind == "input":
        return ("fc/2", "set_input", {"channel": rng.randint(1, 16), "value": on})
    if kind == "analog":
        return ("fc/4", "set_analog", {"channel": rng.randint(1, 8),
                                       "value": rng.choice((0.0, 2.5, 9.0))})
    if kind == "shaft":
        return ("fc/7", "set_shaft_speed", {"encoder": rng.randint(1, 2),
                                            "rpm": rng.choice((0.0, 0.0, 60.0))})
    if kind == "short":
        return ("fc/3", "output_short", {"channel": rng.randint(1, 4), "active": on})
    if kind == "failure":
        return (f"fc/{slot}", "module_failure", {"active": rng.random() < 0.3})
    if kind == "send":
        return ("feeder", "send", {"on": rng.random() < 0.6,
                                   "cycle_ms": rng.choice((1, 1, 4, 60))})
    return ("feeder", "request", {"state": rng.choice(("INIT", "PREOP", "SAFEOP", "OP", "OP",
                                                       "BOOT"))})


def frames_op(rng: random.Random) -> Op:
    """Frames starting and stopping at every cycle length around the activity window, with
    AL control, the cable and the supply: where frames_quiet and the activity bound matter."""
    r = rng.random()
    if r < 0.5:
        return ("feeder", "send", {"on": rng.random() < 0.5, "cycle_ms": rng.choice((1, 4, 60))})
    if r < 0.8:
        return ("feeder", "request", {"state": rng.choice(("INIT", "PREOP", "OP", "OP"))})
    if r < 0.9:
        return ("fc", "link", {"connected": rng.random() < 0.7})
    return ("fc", "power", {"on": rng.random() < 0.8})


def settle(rig: Rig, feeder: bool) -> None:
    """Scan done; with the feeder, frames on and the coupler in OP (the default rig's idle)."""
    rig.advance(4_000)
    if feeder:
        rig.apply("feeder", "send", {"on": True})
        for state in ("PREOP", "SAFEOP", "OP"):
            rig.apply("feeder", "request", {"state": state})
            rig.advance(5)
        rig.take_events()


def run(seed: int, rounds: int, feeder: bool, ops: Callable[[random.Random], Op] | None = None
        ) -> int:
    def make() -> Rig:
        rig = build(seed, feeder)
        settle(rig, feeder)
        return rig

    return differential(make, ops or (lambda rng: op(rng, feeder)), seed, rounds)


def sizes(full: bool) -> tuple[int, int]:
    """(seeds, rounds per seed)."""
    return (12, 160) if full else (2, 40)


def test_single_coupler_spans_are_exact(full: bool) -> None:
    seeds, rounds = sizes(full)
    skipped = sum(run(seed, rounds, feeder=False) for seed in range(seeds))
    assert skipped > seeds * rounds * 100  # INIT idle and unpowered spans are long


def test_coupler_with_frames_spans_are_exact(full: bool) -> None:
    seeds, rounds = sizes(full)
    skipped = sum(run(100 + seed, rounds, feeder=True) for seed in range(seeds))
    assert skipped > seeds * rounds * 100


def test_frames_coming_and_going_spans_are_exact(full: bool) -> None:
    seeds, rounds = sizes(full)
    skipped = sum(run(200 + seed, rounds, True, frames_op) for seed in range(seeds))
    assert skipped > seeds * rounds * 100


def test_idle_op_spans_end_at_the_activity_window() -> None:
    """The default rig's idle: OP, frames every ms: spans of the activity window; without
    frames the span ends where LINK activity would stop; unpowered it has no end."""
    rig = build(7, feeder=True)
    settle(rig, feeder=True)
    fc = rig.devices["fc"]
    assert fc.esm.state is AlState.OP and fc.snapshot()["scan"]["done"] == len(MODULES)
    rig.advance(3)
    now = fc.now_us
    assert fc.frames_quiet()
    assert fc.quiet_until(STEP_US) == now + ACTIVITY_WINDOW_US
    before = rig.skipped_steps
    rig.advance(1_000)
    assert rig.skipped_steps - before >= 1_000 - 1_000 // 50 - 2
    rig.apply("feeder", "send", {"on": False})
    rig.advance(10)
    assert fc.quiet_until(STEP_US) == fc.now_us + ACTIVITY_WINDOW_US - 10 * STEP_US
    rig.advance(100)  # activity off (one full step), then quiet for good
    assert fc.quiet_until(STEP_US) - fc.now_us > 10**6 * STEP_US
    assert not fc.frames_quiet()  # a frame now would light LINK activity
    rig.apply("fc", "power", {"on": False})
    assert fc.quiet_until(STEP_US) - fc.now_us > 10**6 * STEP_US and fc.frames_quiet()


def test_the_sm_watchdog_expires_right_after_a_span() -> None:
    """OP, the frames stop: once LINK activity has lapsed the span runs up to the last step
    within the SM watchdog time (100 ms after the last frame, not one step more), and the
    step after it takes the coupler to SAFEOP with 0x001B (docs/fastcat-coupler.md "SM
    watchdog"), on the skipping rig as on the stepping one."""
    def make() -> Rig:
        rig = build(9, feeder=True)
        settle(rig, feeder=True)
        rig.advance(3)
        rig.apply("feeder", "send", {"on": False})
        return rig

    skipping, stepping = make(), plain(make())
    fc = skipping.devices["fc"]
    assert isinstance(fc, FastCat) and fc.esm.state is AlState.OP
    last = fc.last_frame_us
    assert last is not None and last == fc.now_us
    advance_alike(skipping, stepping, ACTIVITY_WINDOW_US // STEP_US + 2, "activity lapse")
    assert lines(skipping.take_events()) == lines(stepping.take_events())
    assert fc.quiet_until(STEP_US) == last + SM_WATCHDOG_US  # the last step still in OP
    before = skipping.skipped_steps
    stepped = advance_alike(skipping, stepping, 200, "watchdog")
    assert skipping.skipped_steps - before >= 40  # the span up to the watchdog was skipped
    assert rig_state(skipping) == rig_state(stepping)
    events = [r for r in (e.to_record() for e in stepped) if r["event"] in ("al_status", "state")]
    assert [(r["t"], r["event"], r.get("code"), r.get("to")) for r in events] == [
        ((last + SM_WATCHDOG_US + STEP_US) / 1e6, "al_status", "0x001B", None),
        ((last + SM_WATCHDOG_US + STEP_US) / 1e6, "state", None, "SAFEOP")]
    assert fc.quiet_until(STEP_US) - fc.now_us > 10**6 * STEP_US  # SAFEOP: no watchdog


def test_busy_coupler_has_no_span() -> None:
    rig = build(8, feeder=False)
    rig.advance(10)
    fc = rig.devices["fc"]
    assert fc.scan is not None and fc.quiet_until(STEP_US) == fc.now_us  # scanning
    rig.advance(4_000)
    rig.apply("fc/7", "set_shaft_speed", {"encoder": 1, "rpm": 100.0})
    rig.advance(5)
    assert fc.quiet_until(STEP_US) == fc.now_us  # an encoder turning
    assert fc.quiet_until(2 * STEP_US) == fc.now_us  # another step length than the settled


def couple(seed: int) -> FastCat:
    """A coupler alone in OP, frames every ms since OP: settled, LINK active."""
    fc = FastCat("fc", random.Random(seed), [(m, {}) for m in MODULES], flash=MemoryFlash())
    now = 0
    for _ in range(4_000):
        now += STEP_US
        fc.step(now)
        fc.exchange_frame(now)
        fc.take_emergencies()
        if now == 3_000_000:
            for state in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
                fc.request_state(state)
    fc.drain_events()
    return fc


@pytest.mark.parametrize("frames", [0, 1, 7, 49])
def test_skip_frames_is_n_frames(frames: int) -> None:
    """Slave step then frame, once per ms, against skip_to + skip_frames: the same state."""
    stepped, skipped = couple(3), couple(3)
    assert deep_state(stepped) == deep_state(skipped)
    assert stepped.esm.state is AlState.OP and stepped.frames_quiet()
    start = stepped.now_us
    until = stepped.quiet_until(STEP_US)
    assert until - start == ACTIVITY_WINDOW_US
    steps = (until - start) // STEP_US
    for i in range(1, steps + 1):
        stepped.step(start + i * STEP_US)
        if i <= frames:
            stepped.exchange_frame(start + i * STEP_US)
    skipped.skip_to(until, STEP_US)
    skipped.skip_frames(frames, start + frames * STEP_US)
    assert not stepped.drain_events() and not skipped.drain_events()
    assert deep_state(stepped) == deep_state(skipped)
