"""The steady jog's tick (devices/servo/ticking.py ``_cruise_tick``) does what the full tick does.

docs/servo-drive.md §Step cost in motion: a full tick that took the steady jog's path (velocity
mode at its commanded speed, enabled, motor free, no input moving) records its inputs; the
next ticks, with nothing from outside in between, run only the arithmetic. A drive with
``FAST_CRUISE`` off runs every tick in full; a seeded run of commands between stretches of
jogging (writes of the speed and of the following-error window, the halt bit, TEN / IEN, a
jam, alarms, power, the limit and home switches crossed at speed, other step lengths) must
give both the same events every step and the same snapshot and full state after each stretch.
A recovery (about 4 commands in 10) brings the drive back to a jog, so that most stretches
cruise: it waits for a flash save to end, then resets, enables and jogs (see RECOVER).
"""

from __future__ import annotations

import random
from typing import Any

import pytest

from app.rig import Rig
from devices.device import CommandError
from devices.flash import MemoryFlash
from devices.od import SdoAbort
from devices.servo.drive import DriveConfig, ServoDrive
from devices.servo.ds402 import State
from devices.servo.stillness import state_key


class FullDrive(ServoDrive):
    FAST_CRUISE = False


Op = tuple[str, dict[str, Any]]
# Back to a jog: the consents up, a following-error window the jogs keep (R03 as low as 1 or
# 50, left by an earlier write, stopped every later jog with alarm 16 within R04 ms), the
# reset, then the enable (R00 = 0, then 3: seed 004 ch. 2's reset with the enable off).
RECOVER: list[Op] = [("power", {"on": True}), ("jam_load", {"active": False}),
                     ("clear_alarm", {"code": "16"}),
                     *[("set_input", {"name": name, "value": name in ("ten", "ien")})
                       for name in ("ten", "ien", "home", "neg_limit", "latch", "select")],
                     ("write_register", {"register": 3, "value": 20_000}),
                     ("alarm_reset", {}), ("enable", {"on": True})]


def random_ops(rng: random.Random) -> list[Op]:
    """Mostly a jog (after a recovery), else one command that may land inside a cruise."""
    speed: Op = ("write_register", {"register": 12,
                                    "value": rng.choice((600, 3000, 12000, 30000))})
    if rng.random() < 0.4:
        return [*RECOVER, speed, ("jog", {"direction": rng.choice((-1, 1))})]
    return [rng.choice([
        speed, ("jog", {"direction": rng.choice((-1, 0, 1))}),
        ("controlword", {"value": rng.choice((0x0F, 0x10F, 0x0B, 0x07))}),
        ("set_input", {"name": rng.choice(("ten", "ien", "latch", "start", "select", "home")),
                       "value": rng.random() < 0.5}),
        ("jam_load", {"active": rng.random() < 0.5}),
        ("inject_alarm", {"code": "16"}),
        ("power", {"on": rng.random() < 0.7}),
        ("write_register", {"register": rng.choice((3, 4)),
                            "value": rng.choice((1, 50, 20_000, 0xFFFF_FFFF))}),
        ("write_register", {"register": 13, "value": rng.randint(0, 20_000)}),
        ("analog_input", {"volts": rng.choice((0.0, 2.5, -5.0))}),
        ("save", {}),
    ])]


def step_both(drives: list[ServoDrive], t_us: int) -> None:
    for drive in drives:
        drive.step(t_us)
    assert drives[0].drain_events() == drives[1].drain_events()


def await_answer(drives: list[ServoDrive], rigs: list[Rig], t_us: int) -> int:
    """Before a recovery: the drive answers nothing for the 3 s of a flash save (seed 004
    ch. 2), and a save asked for during a jog waits for IEN low (ch. 4): let it run, then
    wait for its end, else every command of the recovery is refused. The time reached."""
    drive = drives[0]
    if drive.save_pending and drive.powered and not drive.saving:
        op: Op = ("set_input", {"name": "ien", "value": False})
        assert outcome(rigs[0], op) == outcome(rigs[1], op)
        t_us += 1000
        step_both(drives, t_us)
    while drive.saving:
        t_us += 1000
        step_both(drives, t_us)
    return t_us


def off_a_limit(drive: ServoDrive, jog: Op) -> Op:
    """The recovery's jog leaves an actuated limit switch: into it the motor presses the
    end stop, and a -1 jog on the negative limit (3000 units from the start) never cruised."""
    g, theta = drive.geometry, drive.plant.theta
    if theta <= g.neg_limit or theta >= g.pos_limit:
        return ("jog", {"direction": 1 if theta <= g.neg_limit else -1})
    return jog


def outcome(rig: Rig, op: Op) -> str:
    try:
        return repr(rig.apply("drive", *op))
    except (CommandError, SdoAbort) as exc:
        return f"refused: {exc}"


@pytest.mark.parametrize("seed", [1, 2, *(pytest.param(s, marks=pytest.mark.full)
                                          for s in (3, 4, 5))])
def test_the_cruise_tick_equals_the_full_tick(seed: int) -> None:
    rng = random.Random(seed)
    config = DriveConfig(start_position=-57_000.0)  # near the negative limit, home ahead
    fast = ServoDrive("drive", random.Random(7), config, MemoryFlash())
    full = FullDrive("drive", random.Random(7), config, MemoryFlash())
    rigs = [Rig("fast", {"drive": fast}), Rig("full", {"drive": full})]
    t_us, cruising = 0, 0
    for _ in range(120):
        ops = random_ops(rng)
        if ops[0] is RECOVER[0]:
            t_us = await_answer([fast, full], rigs, t_us)
            ops[-1] = off_a_limit(fast, ops[-1])
        for op in ops:
            assert outcome(rigs[0], op) == outcome(rigs[1], op), op
        dt = rng.choice((1000, 1000, 1000, 250, 2000))
        for _ in range(rng.choice((1, 3, 50, 400, 1500))):
            t_us += dt
            for drive in (fast, full):
                drive.step(t_us)
            assert fast.drain_events() == full.drain_events()
            cruising += fast._cruise is not None
        assert fast.snapshot() == full.snapshot()
        assert state_key(fast) == state_key(full)
        assert fast.regs == full.regs and fast.params == full.params
    assert full._cruise is None  # never recorded with the switch off
    assert cruising > 10_000  # the fast drive did cruise


def test_a_jog_cruises_and_a_write_ends_the_record() -> None:
    """After the ramp a jog's ticks take the cruise; a register write (from outside) makes the
    next tick a full one, which records again."""
    drive = ServoDrive("drive", random.Random(7), DriveConfig(start_position=300_000.0),
                       MemoryFlash())
    rig = Rig("drive", {"drive": drive})
    calls: list[float] = []
    original = drive._cruise_tick
    drive._cruise_tick = (  # type: ignore[method-assign]
        lambda dt, *rest: calls.append(dt) or original(dt, *rest))
    t_us = 0

    def run(ms: int) -> None:
        nonlocal t_us
        for _ in range(ms):
            t_us += 1000
            drive.step(t_us)

    run(100)
    rig.apply("drive", "enable", {"on": True})
    rig.apply("drive", "jog", {"direction": 1})
    run(1000)
    assert drive.state is State.OPERATION_ENABLED and drive.plant.omega > 0.0
    assert drive._cruise is not None and len(calls) > 500
    before = len(calls)
    drive.write_register(3, 20_000)  # the following-error window: from outside
    assert drive._touched
    run(1)
    assert len(calls) == before  # a full tick ...
    assert drive._cruise is not None  # ... which recorded again
    run(1)
    assert len(calls) == before + 1


@pytest.mark.parametrize("step_us", [1000, 2000])
def test_the_cruise_raises_the_position_overflow_at_the_full_ticks_step(step_us: int) -> None:
    """Alarm 15 (R06 no longer fits S32) reached while cruising: the cruise's own check, at
    the step the full tick raises it (a coarse feed constant and a fast motor bring the axis
    to 2^31 units in about 82 s). In 2 ms steps (after one of 1 ms) the alarm comes from the
    first of a step's two ticks, and the second one must be the full tick's too."""
    config = DriveConfig(feed_constant=0x3FFFF, max_speed_rpm=12_000.0, pos_limit=3e9)
    fast = ServoDrive("drive", random.Random(7), config, MemoryFlash())
    full = FullDrive("drive", random.Random(7), config, MemoryFlash())
    for drive in (fast, full):
        rig = Rig(drive.__class__.__name__, {"drive": drive})
        for register in (10, 12, 13):  # acceleration, profile and target velocity
            rig.apply("drive", "write_register", {"register": register, "value": 50_000_000})
        rig.apply("drive", "write_register", {"register": 3, "value": 0xFFFF_FFFF})  # no R03
        rig.apply("drive", "enable", {"on": True})
        rig.apply("drive", "jog", {"direction": 1})
    t_us, cruising, raised = 0, 0, None
    span = 1000
    while raised is None and t_us < 90_000_000:
        t_us += span
        span = step_us
        for drive in (fast, full):
            drive.step(t_us)
        cruising += fast._cruise is not None
        events = fast.drain_events()
        assert events == full.drain_events()
        raised = next((event.t_us for event in events
                       if getattr(event, "code", None) == "15"), None)
    assert raised == t_us - step_us + 1000  # the step's first tick
    assert raised is not None and cruising > 80_000_000 // step_us  # reached inside a cruise
    assert fast.snapshot() == full.snapshot()
    assert state_key(fast) == state_key(full)


def test_an_alarm_raised_inside_a_cruise_ends_it_within_a_long_step() -> None:
    """Seeds 3 and 4 of the --full run, reduced: a 2 ms step runs two 1 ms ticks; alarm 16
    (R03 exceeded for longer than R04) raised by the first, a cruise tick, puts the drive in
    Fault, and the second tick must be the full tick's (the fault's stop), not another
    cruise of the jog the alarm ended."""
    drives = [ServoDrive("drive", random.Random(7), DriveConfig(), MemoryFlash()),
              FullDrive("drive", random.Random(7), DriveConfig(), MemoryFlash())]
    rigs = [Rig("rig", {"drive": drive}) for drive in drives]
    t_us, cruised = 0, False

    def run(ms: int) -> None:
        nonlocal t_us
        for _ in range(ms):
            t_us += 1000
            for drive in drives:
                drive.step(t_us)
            assert drives[0].drain_events() == drives[1].drain_events()

    run(100)  # the boot
    for op in [("write_register", {"register": 12, "value": 3000}), ("enable", {"on": True}),
               ("jog", {"direction": -1})]:
        assert outcome(rigs[0], op) == outcome(rigs[1], op), op
    run(1000)
    assert drives[0].state is State.OPERATION_ENABLED and drives[0]._cruise is not None
    for op in [("write_register", {"register": 3, "value": 1}),  # the window: 1 unit
               ("write_register", {"register": 4, "value": 50})]:  # for more than 50 ms
        assert outcome(rigs[0], op) == outcome(rigs[1], op), op
    for _ in range(40):  # 80 ticks: alarm 16 at the 51st, the first tick of a step
        t_us += 2000
        for drive in drives:
            drive.step(t_us)
        cruised = cruised or drives[0]._cruise is not None
        events = drives[0].drain_events()
        assert events == drives[1].drain_events()
        assert drives[0].snapshot() == drives[1].snapshot()
        assert state_key(drives[0]) == state_key(drives[1])
    assert cruised and drives[0].state is State.FAULT
