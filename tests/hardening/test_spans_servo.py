"""Quiet spans of the servo drive are exact (docs/servo-drive.md "Quiet spans").

A drive whose last checked step of the rig's length changed nothing but its current meter's
filter says it is quiet without end (``ServoDrive.quiet_until``) and ``skip_to`` moves the clock
and the filter, tick by tick, as the steps would. Checked by the differential harness
(tests/hardening/span_runs.py): single-drive rigs (Modbus, CANopen, EtherCAT fieldbus; 1 ms and
multi-tick / sub-tick step lengths) take the same random commands as a rig stepping one step at
a time, and must give the same events, snapshots and deep state after every stretch; the
skipping rig must have skipped. And directly: a drive whose filter is still settling, skipped
``n`` steps, equals one stepped ``n`` times.

The rig of one ``[[servo]]`` also holds the drive's CANopen node (``<id>-can``), and with
``fieldbus = "ethercat"`` its CoE slave and an EtherCAT master; each has quiet spans of its own,
so the rig skips only where all of them agree.

Reduced (CI, well under 30 s): 3 rigs x 40 rounds; ``--full``: 6 rigs x 300 rounds.
"""

from __future__ import annotations

import random

import pytest
from span_runs import Op, deep_state, differential
from test_still_steps import random_op

from app.rig import Rig
from app.rig_config import build_rig, parse_rig_spec
from devices.flash import MemoryFlash
from devices.servo import ds402
from devices.servo.drive import DriveConfig, ServoDrive

RIG = """
[rig]
name = "one drive"
seed = {seed}
step_ms = {step_ms}

[[servo]]
id = "drive"
fieldbus = "{fieldbus}"
node_id = 4
ten_wired = true
ien_wired = true
flash = ":memory:"
"""

CASES = [  # (fieldbus, step_ms, seed)
    ("modbus", 1, 1),
    ("canopen", 1, 2),
    ("ethercat", 3.5, 3),  # a step of 4 ticks, the last one short
    pytest.param("modbus", 0.25, 4, marks=pytest.mark.full),  # a tick shorter than 1 ms
    pytest.param("ethercat", 1, 5, marks=pytest.mark.full),
    pytest.param("modbus", 2, 6, marks=pytest.mark.full),
]


def one_drive_rig(fieldbus: str, step_ms: float, seed: int) -> Rig:
    rig = build_rig(parse_rig_spec(RIG.format(fieldbus=fieldbus, step_ms=step_ms, seed=seed)))
    rig.advance(100)  # booted (50 ms self test), standing, switched on disabled
    return rig


def drive_op(rng: random.Random) -> Op:
    """test_still_steps' commands to a drive (every action the drive family takes), aimed at
    the one drive; CANopen frames become a plain step instead (the node is left out)."""
    target, action, args = random_op(rng)
    if target == "drive_co-can":
        return "drive", "read_register", {"register": 5}
    return "drive", action, args


@pytest.mark.parametrize(("fieldbus", "step_ms", "seed"), CASES)
def test_quiet_spans_are_exact(fieldbus: str, step_ms: float, seed: int, full: bool) -> None:
    skipped = differential(lambda: one_drive_rig(fieldbus, step_ms, seed), drive_op,
                           seed=seed, rounds=300 if full else 40)
    assert skipped > 2000  # the drive did say quiet, and the rig did skip


def test_idle_states_give_long_spans() -> None:
    """The idle states of the default rig's drives: each is quiet without end once its first
    checked step passed, and a rig of one drive skips nearly all of a long stretch."""
    rig = one_drive_rig("modbus", 1, 7)
    drive = rig.devices["drive"]
    assert isinstance(drive, ServoDrive)
    states = [
        ("powered, disabled", None),
        ("enabled, standing (filter settling)", ("drive", "enable", {"on": True})),
        ("homed, standing", ("drive", "home", {})),
        ("alarm", ("drive", "inject_alarm", {"code": "16"})),
        ("alarm reset, disabled", ("drive", "alarm_reset", {})),
        ("powered off", ("drive", "power", {"on": False})),
    ]
    for name, op in states:
        if op is not None:
            rig.apply(*op)
        rig.advance(20_000)  # homing and fault reactions done, standing
        before = rig.skipped_steps
        rig.advance(3_000)
        assert drive.quiet_until(1_000) - drive.now_us > 10**6, name
        assert rig.skipped_steps - before >= 2_990, name


@pytest.mark.parametrize("step_us", [1_000, 3_500, 250])
def test_skip_to_moves_the_filter_as_steps_do(step_us: int) -> None:
    """Right after a disable the RMS filter decays for minutes: skip_to must move it exactly."""
    drives = [ServoDrive("servo", random.Random(7), DriveConfig(), MemoryFlash())
              for _ in range(2)]
    t_us = 0
    for op in ((None, 60), ("enable", 500), ("disable", 300)):
        for d in drives:
            if op[0] == "enable":
                d.apply("enable", {"on": True})
            elif op[0] == "disable":
                d.apply("enable", {"on": False})
        for _ in range(op[1]):
            t_us += step_us
            for d in drives:
                d.step(t_us)
    stepped, skipped = drives
    assert stepped.drain_events() == skipped.drain_events()
    assert skipped._still.dt is None and skipped.meter.rms > 1.0  # settling, not still
    until = skipped.quiet_until(step_us)
    assert until >= t_us + 1_000 * step_us
    for n in (1, 2, 997):
        for _ in range(n):
            t_us += step_us
            stepped.step(t_us)
        skipped.skip_to(t_us, step_us)
        assert deep_state(skipped) == deep_state(stepped), n
        assert stepped.drain_events() == skipped.drain_events() == []
    # and the two go on alike: a command, then steps
    for d in drives:
        d.apply("enable", {"on": True})
    for _ in range(50):
        t_us += step_us
        for d in drives:
            d.step(t_us)
    assert stepped.drain_events() == skipped.drain_events()
    assert deep_state(skipped) == deep_state(stepped)


@pytest.mark.parametrize("step_us", [1_000, 3_500, 250])
def test_a_span_ends_before_zero_speed_comes_on(step_us: int) -> None:
    """A standing drive in mode 3 says "asse fermo" (R05 bit 7, 0x6041 bit 12) R17 = 10 ms
    after its speed went within R16, by the clock and with nothing else changing. The CANopen
    node's TPDOs and the CoE slave's inputs read the status word at every step of a span, so
    the drive's span ends before the bit comes on (docs/servo-drive.md "Quiet spans")."""
    d = ServoDrive("servo", random.Random(7), DriveConfig(), MemoryFlash())
    t_us = 0
    while t_us < 100_000:
        t_us += step_us
        d.step(t_us)
    d.apply("write_register", {"register": 1, "value": 3})  # standing, switched on disabled
    word, spans = d.statusword, 0
    assert not word & ds402.SW_MODE_12
    while d.statusword == word:
        until = d.quiet_until(step_us)
        assert until - d.now_us <= 10_000, "a span across the zero-speed instant"
        spans += until > d.now_us
        while d.now_us < until:
            t_us += step_us
            d.step(t_us)
            assert d.statusword == word
        t_us += step_us
        d.step(t_us)
    assert d.statusword == word | ds402.SW_MODE_12
    # quiet before the bit came on, up to it (at 3.5 ms the still proof comes too late)
    assert spans or step_us > 1_000
    t_us += step_us
    d.step(t_us)
    assert d.quiet_until(step_us) - d.now_us > 10**6  # and without end once it is on
