"""Quiet spans of the drive's EtherCAT CoE slave (docs/ethercat-coe.md "Quiet spans").

Two kinds of test:

- frames: two identical drive + slave pairs in a quiet state; one is stepped as the rig and the
  master do (drive step, slave step, then the master's frame, every ms), the other takes the
  slave's ``skip_to`` + ``skip_frames`` over the span ``quiet_until`` gave, its drive stepped
  normally. Events and deep state (rngs included) must be the same.
- differential (tests/hardening/span_runs.py): rigs of the drive, its slave and a stand-in master
  (:class:`FrameSource`: a frame per step while cycling, the mailbox read, skipping with
  ``frames_quiet`` / ``skip_frames`` as the contract has the master do), one skipping spans
  with ``Rig.advance``, one stepping, under random ops (ESM requests, frames on / off, link,
  power, outputs, objects, slots, alarms); the drive with its own quiet spans.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from typing import Any

import pytest
from span_runs import deep_state, lines, outcome, plain, rig_state

from app.clock import SimClock
from app.rig import Rig
from devices.coe import drive_slave as ds
from devices.coe.drive_slave import DriveEcatSlave
from devices.device import DeviceModel
from devices.ethercat import AlState
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

MS = 1_000
ALARMS = ("16", "34", "7")  # an event alarm, the sync timeout, a controller alarm
INIT, PREOP, SAFEOP, OP = AlState.INIT, AlState.PREOP, AlState.SAFEOP, AlState.OP
FAR = 1 << 50


# ---- a stand-in master: a frame per step while cycling -----------------------------------------
class FrameSource(DeviceModel):
    """What the built-in master does to this slave each cycle, cut down: the frame (when the
    slave is reachable), then its mailbox. Quiet while the slave's frames are quiet and its
    mailbox has nothing to hand over; skipping gives the frames to ``skip_frames``."""

    KIND = "frame_source"

    def __init__(self, device_id: str, slave: DriveEcatSlave) -> None:
        super().__init__(device_id=device_id)
        self.slave = slave
        self.cycling = True
        self.frames = 0
        self.emergencies: list[bytes] = []

    def step(self, now_us: int) -> None:
        super().step(now_us)
        slave = self.slave
        if self.cycling:
            slave.exchange_frame(now_us)  # returns at once when not reachable
            self.frames += 1
        self.emergencies += slave.take_emergencies()

    def _mailbox_quiet(self) -> bool:
        slave = self.slave
        return not slave.emergencies.pending or not slave.reachable() \
            or not slave.esm.at_least(PREOP)

    def quiet_until(self, step_us: int) -> int:
        if not self._mailbox_quiet() or (self.cycling and not self.slave.frames_quiet()):
            return self.now_us
        return self.now_us + FAR * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        n = (t_us - self.now_us) // step_us  # one frame per step
        self.now_us = t_us
        if self.cycling and n > 0:
            self.frames += n
            if self.slave.reachable():
                self.slave.skip_frames(n, t_us)

    def snapshot(self) -> dict[str, Any]:
        return {"cycling": self.cycling, "frames": self.frames,
                "emergencies": [e.hex() for e in self.emergencies]}


def _pair(seed: int = 7) -> tuple[ServoDrive, DriveEcatSlave]:
    drive = ServoDrive("drive_ec", random.Random(seed),
                       DriveConfig(fieldbus="ethercat", node_id=3), MemoryFlash())
    slave = DriveEcatSlave("drive_ec-ecat", drive, random.Random("1/drive_ec-ecat"))
    return drive, slave


def build() -> Rig:
    drive, slave = _pair()
    source = FrameSource("master", slave)
    rig = Rig(name="coe", devices={"drive_ec": drive, "drive_ec-ecat": slave, "master": source},
              clock=SimClock(step_us=MS), seed=1)
    rig.take_events()
    return rig


def _go(rig: Rig, *states: AlState) -> None:
    for state in states:
        rig.devices["drive_ec-ecat"].request_state(state)  # type: ignore[attr-defined]
        rig.take_events()
        rig.step()


# ---- the ops of the differential ---------------------------------------------------------------
Op = Callable[[Rig], Any]
STATES = (INIT, PREOP, SAFEOP, OP, AlState.BOOT)


def _apply(target: str, action: str, **args: Any) -> Op:
    return lambda rig: outcome(rig, (target, action, args))


def _request(state: AlState) -> Op:
    def op(rig: Rig) -> Any:
        rig.devices["drive_ec-ecat"].request_state(state)  # type: ignore[attr-defined]
        return None
    return op


def _cycling(on: bool) -> Op:
    def op(rig: Rig) -> Any:
        rig.devices["master"].cycling = on  # type: ignore[attr-defined]
    return op


def _set_link(on: bool) -> Op:  # the master's way: no LED refresh until the next step
    return lambda rig: rig.devices["drive_ec-ecat"].set_link(on)  # type: ignore[attr-defined]


def _up_to_op(rig: Rig) -> Any:
    for state in (PREOP, SAFEOP, OP):
        rig.devices["drive_ec-ecat"].request_state(state)  # type: ignore[attr-defined]


def random_op(rng: random.Random) -> tuple[str, Op]:
    slave, drive = "drive_ec-ecat", "drive_ec"
    choices: list[tuple[int, str, Callable[[], Op]]] = [
        (6, "request", lambda: _request(rng.choice(STATES))),
        (4, "up_to_op", lambda: _up_to_op),
        (3, "cycling", lambda: _cycling(rng.random() < 0.7)),
        (2, "link", lambda: _apply(slave, "link", connected=rng.random() < 0.6)),
        (2, "set_link", lambda: _set_link(rng.random() < 0.6)),
        (2, "power", lambda: _apply(drive, "power", on=rng.random() < 0.7)),
        (2, "outputs", lambda: _apply(slave, "set_outputs", data=rng.choice(
            ("00 00 00 00 00 00", "06 00 00 00 00 00", "80 00 00 00 00 00",
             "0F 00 10 00 00 00", "00 00")))),
        (2, "write_object", lambda: _apply(slave, "write_object", **rng.choice((
            {"index": 0x1003, "sub": 0, "value": 0}, {"index": 0x6060, "sub": 0, "value": 8},
            {"index": 0x6060, "sub": 0, "value": 7}, {"index": 0x6040, "sub": 0, "value": 6},
            {"index": 0x1C12, "sub": 0, "value": 0}, {"index": 0x1600, "sub": 0, "value": 0},
            {"index": 0x1C12, "sub": 0, "value": 1})))),
        (1, "read_object", lambda: _apply(slave, "read_object", index=0x1001, sub=0)),
        (1, "slot", lambda: _apply(slave, "select_slot", slot=rng.choice(
            ("position", "interpolated", "velocity", "csp")))),
        (2, "alarm", lambda: _apply(drive, "inject_alarm", code=rng.choice(ALARMS))),
        (2, "clear_alarm", lambda: _apply(drive, "clear_alarm", code=rng.choice(ALARMS))),
        (2, "alarm_reset", lambda: _apply(drive, "alarm_reset")),
        (2, "nothing", lambda: (lambda rig: None)),
    ]
    total = sum(w for w, _n, _f in choices)
    pick = rng.uniform(0, total)
    for weight, name, make in choices:
        pick -= weight
        if pick <= 0:
            return name, make()
    return choices[-1][1], choices[-1][2]()


def differential(seed: int, rounds: int,
                 lengths: tuple[int, ...] = (1, 3, 20, 200, 900, 3000)) -> int:
    """span_runs.differential with ops that are calls on the rig (ESM requests and the frames
    are not actions); the steps the skipping rig skipped."""
    rng = random.Random(seed)
    skipping, stepping = build(), plain(build())
    for rig in (skipping, stepping):
        rig.advance(60)  # past the drive's self test
        _up_to_op(rig)
        rig.take_events()
    for _ in range(rounds):
        name, op = random_op(rng)
        assert repr(op(skipping)) == repr(op(stepping)), name
        assert lines(skipping.take_events()) == lines(stepping.take_events()), name
        steps = rng.choice(lengths)
        assert lines(skipping.advance(steps)) == lines(stepping.advance(steps)), (name, steps)
        assert rig_state(skipping) == rig_state(stepping), (name, steps)
    return skipping.skipped_steps


@pytest.mark.parametrize("seed", [1, 2])
def test_skipping_rig_matches_stepping(full: bool, seed: int) -> None:
    rounds = 400 if full else 25
    skipped = differential(seed, rounds)
    assert skipped > rounds * 50, skipped


@pytest.mark.full
@pytest.mark.parametrize("seed", range(10, 20))
def test_skipping_rig_matches_stepping_more_seeds(seed: int) -> None:
    assert differential(seed, 300) > 0


# ---- frames against skip_frames ----------------------------------------------------------------
def _bench_to(state: AlState, seed: int = 7) -> tuple[ServoDrive, DriveEcatSlave]:
    drive, slave = _pair(seed)
    t = 0
    path = {INIT: (), PREOP: (PREOP,), SAFEOP: (PREOP, SAFEOP), OP: (PREOP, SAFEOP, OP)}[state]
    requests = dict(zip(range(60, 60 + len(path)), path, strict=True))
    for k in range(1, 200):  # boot, the requests, then a settled drive and LEDs
        t = k * MS
        drive.step(t)
        slave.step(t)
        slave.exchange_frame(t)
        if k in requests:
            slave.request_state(requests[k])
    drive.drain_events()
    slave.drain_events()
    assert slave.esm.state is state
    return drive, slave


def _stepped(drive: ServoDrive, slave: DriveEcatSlave, until: int, frames: bool) -> list:
    t = slave.now_us
    while t < until:
        t += MS
        drive.step(t)
        slave.step(t)
        if frames:
            slave.exchange_frame(t)  # the master is stepped last
    return lines(drive.drain_events() + slave.drain_events())


def _skipped(drive: ServoDrive, slave: DriveEcatSlave, until: int, frames: bool) -> list:
    start, t = slave.now_us, drive.now_us
    while t < until:  # the drive as it is stepped (a drive with no quiet span of its own)
        t += MS
        drive.step(t)
    slave.skip_to(until, MS)
    if frames:
        slave.skip_frames((until - start) // MS, until)
    return lines(drive.drain_events() + slave.drain_events())


def _compare_spans(state: AlState, frames: bool, spans: int, seed: int = 7) -> list[int]:
    """Spans from quiet_until, each taken both ways, a step where there is none (-1); their
    lengths in steps."""
    a, b = _bench_to(state, seed), _bench_to(state, seed)
    assert deep_state(a) == deep_state(b)
    lengths: list[int] = []
    while len(lengths) < spans:
        now = b[1].now_us
        until = b[1].quiet_until(MS)
        assert until == a[1].quiet_until(MS)
        if until == now:  # not quiet: one step, both stepped
            lengths.append(-1)
            assert _stepped(*a, now + MS, frames) == _stepped(*b, now + MS, frames)
            continue
        until = min(until, now + 300 * MS)
        lengths.append((until - now) // MS)
        if frames:
            assert b[1].frames_quiet() and a[1].frames_quiet()
        assert _stepped(*a, until, frames) == _skipped(*b, until, frames)
        assert deep_state(a) == deep_state(b), (state, frames, until)
    return lengths


@pytest.mark.parametrize("state", [INIT, PREOP, SAFEOP, OP])
def test_frames_against_skip_frames(state: AlState) -> None:
    lengths = _compare_spans(state, True, 8)
    # a frame every ms: every span ends at the L/A activity window (50 ms after the last frame)
    assert lengths == [ds.ACTIVITY_WINDOW_US // MS] * 8


@pytest.mark.parametrize("state", [INIT, PREOP, SAFEOP, OP])
def test_no_frames_spans_end_at_the_window_then_the_watchdog(state: AlState) -> None:
    lengths = _compare_spans(state, False, 6)
    # a span to the window's end, the step the LED stops flickering, then no end but the test's
    # 300; in OP the second span ends at the SM watchdog (last frame + 100 ms), the step after
    # falls to SAFEOP (alarm 34, its emergency next step), then quiet again
    if state is OP:
        assert lengths == [50, -1, 49, -1, 300, 300], lengths
    else:
        assert lengths == [50, -1, 300, 300, 300, 300], lengths


def test_window_shorter_than_the_watchdog() -> None:
    """quiet_until leaves out the watchdog while the activity window runs: it ends first."""
    assert ds.ACTIVITY_WINDOW_US < ds.SM_WATCHDOG_US


def test_outputs_in_op_are_not_quiet_frames() -> None:
    """An outputs image is written to the drive at every frame in OP; even unchanged on a
    standing drive that is no no-op: it touches the drive (its next step runs in full) and
    sets the controlword's source, so frames are not quiet."""
    drive, slave = _bench_to(OP)
    slave.write_outputs(bytes(6))
    assert not slave.frames_quiet()
    _stepped(drive, slave, slave.now_us + 5 * MS, True)
    t = slave.now_us + MS
    drive.step(t)  # a full step (the frame touched it) that leaves it untouched
    slave.step(t)
    before = deep_state(drive)
    assert not drive._touched
    slave.exchange_frame(t)  # the same image again
    assert drive._touched and deep_state(drive) != before
    with pytest.raises(RuntimeError):
        slave.skip_frames(3, slave.now_us)


@pytest.mark.parametrize("case", ["link", "power", "command"])
def test_no_span_after_an_unseen_change(case: str) -> None:
    drive, slave = _bench_to(OP)
    assert slave.quiet_until(MS) > slave.now_us
    if case == "link":
        slave.set_link(False)  # the LED input changes at the next step
    elif case == "power":
        drive.apply("power", {"on": False})
    else:
        drive.apply("inject_alarm", {"code": "16"})
        drive.step(drive.now_us + MS)  # the alarm latches: the slave's next step sends it
    assert slave.quiet_until(MS) == slave.now_us


def test_unreachable_frames_change_nothing() -> None:
    drive, slave = _bench_to(OP)
    slave.set_link(False)
    _stepped(drive, slave, slave.now_us + 200 * MS, False)
    assert slave.frames_quiet()
    before = deep_state(slave)
    slave.skip_frames(10, slave.now_us)
    assert deep_state(slave) == before
    assert slave.quiet_until(MS) >= slave.now_us + 1000 * MS


def test_idle_op_rig_skips_most_steps() -> None:
    """The idle state aimed at: OP, a frame every ms, no outputs image, the drive standing."""
    skipping, stepping = build(), plain(build())
    for rig in (skipping, stepping):
        rig.advance(60)
        _up_to_op(rig)
        rig.take_events()
        assert lines(rig.advance(1000)) == []
    assert skipping.devices["drive_ec-ecat"].esm.state is OP  # type: ignore[attr-defined]
    assert rig_state(skipping) == rig_state(stepping)
    assert skipping.skipped_steps >= 950, skipping.skipped_steps
