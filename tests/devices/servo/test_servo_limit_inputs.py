"""Limit switch inputs are limit switches only when the homing method in force uses them.

Seed 004 ch. 2 (l. 1439-1441, 1488-1494) and ch. 4 (l. 3895-3917): the limit switch and home
inputs are "relativi agli switch utilizzati per la ricerca dello zero assi secondo il metodo di
ricerca utilizzato (homing_method)"; "qualora non si utilizzi in nessun caso quella primaria, si
può liberamente utilizzare l'ingresso come generico digital input", e.g. homing with the home
switch only frees pins 8 and 9. The method in force is the current R18 / 0x6098
(docs/servo-drive.md §Digital I/O).
"""

from __future__ import annotations

import pytest

from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State
from tests.devices.servo.servo_helpers import Sim, make_sim

LIMIT_ACTIVE = 0x0800  # 0x6041 bit 11
NEG_BIT, POS_BIT = 1 << 8, 1 << 9  # R48 / 0x60FD
# the model's methods and the limit switch each one uses (docs/servo-drive.md §Homing)
USES = {1: "neg_limit", 17: "neg_limit", 2: "pos_limit", 18: "pos_limit",
        3: None, 4: None, 19: None, 20: None, 33: None, 34: None, 35: None}


def _jog(sim: Sim, method: int, velocity: int) -> None:
    sim.w(18, method)
    sim.w(1, 3)
    sim.w(13, velocity)
    sim.w(0, 3)
    sim.run(300)


@pytest.mark.parametrize("method", sorted(USES))
@pytest.mark.parametrize(("name", "velocity", "code", "bit"),
                         [("neg_limit", -6000, 20, NEG_BIT), ("pos_limit", 6000, 21, POS_BIT)],
                         ids=["LS1", "LS2"])
def test_a_limit_input_is_a_limit_only_for_a_method_that_uses_it(
        method: int, name: str, velocity: int, code: int, bit: int) -> None:
    sim = make_sim()
    _jog(sim, method, velocity)
    sim.drive.apply("set_input", {"name": name, "value": True})
    sim.run(20)
    d = sim.drive
    assert d.read_register(48) & bit  # the pin reads its level either way
    if USES[method] == name:
        assert d.read_register(46) == code
        assert d.statusword & LIMIT_ACTIVE
    else:  # a plain digital input: the jog goes on, nothing reads it as a limit
        assert d.read_register(46) == 0
        assert d.state is State.OPERATION_ENABLED
        assert not d.statusword & LIMIT_ACTIVE
        assert abs(d.velocity_user) > 5000


def test_the_auditors_home_switch_only_run_keeps_jogging() -> None:
    """R18 = 19 (home switch only): pos_limit high while jogging positive is a digital input."""
    sim = make_sim()
    _jog(sim, 19, 6000)
    sim.drive.apply("set_input", {"name": "pos_limit", "value": True})
    sim.run(10)
    assert sim.drive.state is State.OPERATION_ENABLED
    assert sim.drive.read_register(46) == 0
    assert sim.drive.read_register(48) == 0x600  # pos_limit (9) and home (10)


def test_writing_r18_on_an_active_switch_takes_effect_at_once() -> None:
    """R18 is read every tick: on the switch with method 34 nothing; R18 = 2 makes the same
    active pin a limit (bit 11 on, alarm 21 as the axis keeps moving into it)."""
    sim = make_sim()
    _jog(sim, 34, 6000)
    sim.drive.apply("set_input", {"name": "pos_limit", "value": True})
    sim.run(20)
    assert sim.drive.read_register(46) == 0
    sim.w(18, 2)
    assert sim.drive.read_register(46) == 21
    assert sim.drive.statusword & LIMIT_ACTIVE


def test_r18_on_a_limit_method_standing_on_the_switch_only_lights_bit_11() -> None:
    """Standing on the switch raises nothing (alarms 20 / 21 are for moving into it); moving
    out of it is allowed, moving into it trips the alarm."""
    sim = make_sim()
    sim.w(18, 34)
    sim.drive.apply("set_input", {"name": "neg_limit", "value": True})
    sim.w(1, 3)
    sim.w(0, 3)
    sim.run(50)
    assert not sim.drive.statusword & LIMIT_ACTIVE
    sim.w(18, 1)
    sim.run(50)
    assert sim.drive.statusword & LIMIT_ACTIVE
    assert sim.drive.read_register(46) == 0
    sim.w(13, 3000)
    sim.run(100)
    assert sim.drive.read_register(46) == 0
    sim.w(13, -3000)
    sim.run_until(lambda: sim.drive.read_register(46) == 20, 500)


def test_running_past_an_unused_limit_ends_on_the_end_stop_with_alarm_16() -> None:
    """Default R18 = 34 (markers only): the carriage passes LS2 and reaches the mechanical end
    stop (end_margin_turns beyond it); the following error then trips alarm 16 and the drive
    ends in Fault, the carriage held at the stop (no runaway)."""
    cfg = DriveConfig(neg_limit=-12000, pos_limit=12000)
    sim = make_sim(cfg)
    assert sim.drive.read_register(18) == 34
    sim.w(1, 3)
    sim.w(13, 30000)
    sim.w(0, 3)
    sim.run_until(lambda: sim.drive.read_register(46) != 0, 5_000)
    assert sim.drive.read_register(46) == 16
    sim.run_until(lambda: sim.drive.state is State.FAULT, 2_000)
    sim.run(1000)
    d = sim.drive
    stop = d.geometry.end_stops[1]
    assert d.plant.theta == pytest.approx(stop)
    assert d.read_register(48) & POS_BIT and not d.statusword & LIMIT_ACTIVE

