"""The drive's fast tick (devices/servo/ticking.py) does exactly what the plain tick did.

docs/servo-drive.md §Step cost: the tick leaves out work that cannot change a result (parts
whose inputs say they do nothing, the input levels rebuilt only on a change, the state
machine evaluated only for new inputs). ``PlainDrive`` below is the tick as it was before that
work, every part called every tick; a seeded random run of commands (moves across the home
switch, the markers and the negative limit, homing, jogs, the latch and start inputs, TEN /
IEN, alarms, power, saves, indirect accesses) must give both drives the same events, the same
snapshot and the same full state (``state_key``) after every stretch.
"""

from __future__ import annotations

import random
from typing import Any

import pytest

from app.rig import Rig
from devices.device import CommandError
from devices.flash import MemoryFlash
from devices.od import SdoAbort
from devices.servo import ds402
from devices.servo.drive import DriveConfig, ServoDrive
from devices.servo.ds402 import Command, State
from devices.servo.homing import limits_used
from devices.servo.registers import R
from devices.servo.stillness import state_key


class PlainDrive(ServoDrive):
    """The tick before the step cost work: every part called, every value computed."""

    def _evaluate(self) -> None:
        self._quiet_evaluation = None  # no remembered evaluation
        super()._evaluate()

    def _tick(self, dt: float) -> None:
        lag = self.position_lag_s
        if not self.powered:
            self.plant.step(dt, None, lag)
            self.trajectory.hold(self.plant.theta, self.plant.omega)
            return
        if self.state is State.NOT_READY_TO_SWITCH_ON and self._t_us >= self.boot_until:
            self._transition(Command.SELF_TEST_DONE)
        self.indirect.step(self._t_us)
        self._update_saving()
        self._evaluate()
        monitor = self.mode_logic.monitor
        if monitor is not None:  # zero speed follows the axis in any state (velocity modes)
            monitor.follow_speed(self, self._t_us - round(dt * 1e6))
        theta_before, velocity_before = self.plant.theta, self.trajectory.velocity
        self._move(dt, lag)
        self.meter.update(self, (self.trajectory.velocity - velocity_before) / dt, dt)
        levels = self.input_levels()
        changes = self._changes(self._levels, levels, theta_before, self.plant.theta)
        if levels["start"] and not self._levels.get("start", False):
            self.mode_logic.on_start_input(self)
        self._levels = levels
        confirmed = self.latch.update(levels["latch"], self._t_us, self.position_user)
        if confirmed is not None:
            self.regs[R.LATCHED_POSITION] = confirmed
            self.latched_flag = True
        self.mode_logic.observe(self, changes)
        self._check_limits(levels)
        if self.state is State.OPERATION_ENABLED and self.following_error_exceeded:
            self._fe_ms += dt * 1e3
            if self._fe_ms > self.regs[R.FOLLOWING_ERROR_TIMEOUT]:
                self._fe_ms = 0.0
                self.raise_alarm(16)
        else:
            self._fe_ms = 0.0
        if abs((self.plant.theta - self.theta_zero) * self.feed) > 0x7FFF_FFFF:
            self.raise_alarm(15)

    def _check_limits(self, levels: dict[str, bool]) -> None:
        """Alarms 20 / 21 (LS1 / LS2): moving into an active limit switch outside homing, one
        that the homing method in force (R18) uses."""
        if self.state is not State.OPERATION_ENABLED or self.mode_logic.busy:
            return
        used = limits_used(self.regs[R.HOMING_METHOD])
        velocity = self.trajectory.velocity
        if levels["neg_limit"] and velocity < 0.0 and "neg_limit" in used:
            self.raise_alarm(20)
        elif levels["pos_limit"] and velocity > 0.0 and "pos_limit" in used:
            self.raise_alarm(21)

    def _move(self, dt: float, lag: float) -> None:
        if not self.state.in_torque:
            if self._was_allowed:
                self.mode_logic.halted(self)
                self._was_allowed = False
            self.plant.step(dt, None, lag)
            self.trajectory.hold(self.plant.theta, self.plant.omega)
            return
        if self.state is State.OPERATION_ENABLED:
            allowed = self.motion_allowed
            if allowed:
                self.mode_logic.step(self, dt)
            elif self._was_allowed:
                self.mode_logic.halted(self)
                halting = self.motion_enabled
                self.trajectory.stop(self.limits() if halting else self.quick_stop_limits())
            self._was_allowed = allowed
        self.trajectory.advance(dt)
        self.plant.step(dt, self.trajectory.position, lag, self.motor_vmax_rev)
        standstill = self.trajectory.idle and self.trajectory.velocity == 0.0 \
            and self.plant.standstill
        if standstill and self.state is State.QUICK_STOP_ACTIVE:
            self._transition(Command.STANDSTILL)
        elif standstill and self.state is State.FAULT_REACTION_ACTIVE:
            self._transition(Command.FAULT_REACTION_DONE)


Op = tuple[str, dict[str, Any]]
RECOVER: list[Op] = [("power", {"on": True}), ("clear_alarm", {"code": "16"}),
                     ("clear_alarm", {"code": "9"}), ("jam_load", {"active": False}),
                     *[("set_input", {"name": name, "value": name in ("ten", "ien")})
                       for name in ("ten", "ien", "home", "neg_limit")],
                     ("alarm_reset", {}), ("enable", {"on": True})]


def random_ops(rng: random.Random) -> list[Op]:
    """Commands; half the time a recovery (alarms cleared, enabled) and then a motion.

    Positions reach past the negative limit (-60000) and cross home (-3000) and markers."""
    motion: list[Op] = [
        ("move", {"position": rng.randint(-80_000, 90_000), "relative": rng.random() < 0.2}),
        ("jog", {"direction": rng.choice((-1, 1))}), ("home", {}),
        ("set_mode", {"mode": rng.choice((7, -2, -127))}), ("start", {}),
        ("controlword", {"value": rng.choice((0x0F, 0x1F, 0x81F))}),
    ]
    if rng.random() < 0.5:  # at up to 5 turns/s, so that the stretches cross something
        speed = ("write_register", {"register": 12, "value": rng.choice((3000, 12000, 30000))})
        return [*RECOVER, speed, rng.choice(motion)]
    other: list[Op] = [
        *motion,
        ("enable", {"on": rng.random() < 0.8}), ("stop", {}), ("sync", {}),
        ("jog", {"direction": 0}),
        ("set_mode", {"mode": rng.choice((1, 3, 6, -1))}),
        ("set_input", {"name": rng.choice(("ten", "ien", "latch", "start", "select",
                                           "home", "neg_limit")),
                       "value": rng.random() < 0.5}),
        ("inject_alarm", {"code": rng.choice(("16", "9"))}),
        ("jam_load", {"active": True}),
        ("power", {"on": False}),
        ("save", {}),
        ("controlword", {"value": rng.choice((0, 6, 7, 0x10F, 0x80))}),
        ("write_register", {"register": rng.choice((3, 4, 13)),
                            "value": rng.randint(0, 20_000)}),
        ("write_register", {"register": 18, "value": rng.choice((1, 2, 3, 17, 33, 34))}),
        ("write_register", {"register": 3, "value": 0xFFFF_FFFF}),  # following error off
        ("write_object", {"index": 0x2005, "sub": 0,
                          "value": rng.choice((0x8006, 0x0005, 0x8046))}),
        ("master_encoder", {"rpm": rng.choice((0.0, 300.0, -120.0))}),
        ("analog_input", {"volts": rng.choice((0.0, 2.5, -5.0))}),
        ("pulses", {"count": rng.randint(-5000, 5000)}),
    ]
    return [rng.choice(other)]


def outcome(rig: Rig, op: Op) -> str:
    try:
        return repr(rig.apply("drive", *op))
    except (CommandError, SdoAbort) as exc:
        return f"refused: {exc}"


@pytest.mark.parametrize("seed", [1, *(pytest.param(s, marks=pytest.mark.full) for s in (2, 3))])
def test_fast_tick_equals_the_plain_tick(seed: int, full: bool) -> None:
    rng = random.Random(seed)
    config = DriveConfig(start_position=-57_000.0)  # half a turn from the negative limit
    fast = ServoDrive("drive", random.Random(7), config, MemoryFlash())
    plain = PlainDrive("drive", random.Random(7), config, MemoryFlash())
    rigs = [Rig("fast", {"drive": fast}), Rig("plain", {"drive": plain})]
    t_us, moving = 0, 0
    for _ in range(300 if full else 100):
        ops = random_ops(rng)
        for op in ops:
            assert outcome(rigs[0], op) == outcome(rigs[1], op), op
        dt = rng.choice((1000, 1000, 1000, 250, 2500))
        for _ in range(rng.choice((1, 5, 50, 400, 2000))):
            t_us += dt
            for drive in (fast, plain):
                drive.step(t_us)
            assert fast.drain_events() == plain.drain_events(), ops
            moving += fast.plant.omega != 0.0
        assert fast.snapshot() == plain.snapshot(), ops
        assert state_key(fast) == state_key(plain), ops
    assert moving > 5_000  # the run did move the axis


def test_a_moving_drive_builds_the_input_levels_only_on_a_change() -> None:
    """Jogging clear of every switch: the levels dict of the first tick serves the next ones,
    until an input is driven (the latch here, captured 2 ms later: seed 004 ch. 2)."""
    drive = ServoDrive("drive", random.Random(7), DriveConfig(start_position=300_000.0),
                       MemoryFlash())
    rig = Rig("drive", {"drive": drive})
    t_us = 0

    def run(ms: int) -> None:
        nonlocal t_us
        for _ in range(ms):
            t_us += 1000
            drive.step(t_us)

    run(100)
    rig.apply("drive", "enable", {"on": True})
    rig.apply("drive", "jog", {"direction": 1})
    built: list[tuple[bool, ...]] = []
    original = drive.levels_at
    drive.levels_at = (  # type: ignore[method-assign]
        lambda switches: built.append(switches) or original(switches))
    run(500)
    assert drive.plant.omega > 0.0 and drive.state is State.OPERATION_ENABLED
    assert not drive.cw & ds402.CW_HALT
    assert len(built) <= 1
    assert drive._levels == drive.input_levels()
    rig.apply("drive", "set_input", {"name": "latch", "value": True})
    run(5)
    assert len(built) == 2 and drive._levels == drive.input_levels()
    assert drive.latched_flag  # the tick saw the new level
