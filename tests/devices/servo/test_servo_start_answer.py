"""Home, Start and Move answer why the axis will not move, as Jog does (docs/dashboard.md
"Controls (tab Servo drive)").

A review's run: after an alarm reset that found Ten_cmd held (docs/servo-drive.md
"Re-enabling after an alarm") a trainee pressed Home, then Start: the start bit went to R00,
the drive (Switch on disabled) consumed it and nothing moved, with no word; only Jog's answer
(`motion_blocked`) said to enable again. The commands are still taken, as a master's writes
are: the answer only says why nothing happens.
"""

from __future__ import annotations

from servo_helpers import make_sim

from devices.servo.ds402 import State

FOLLOWING_ERROR = 16


def test_home_start_and_move_on_a_drive_without_torque_say_so() -> None:
    sim = make_sim()
    for action, args in (("home", {}), ("start", {}), ("move", {"position": 100,
                                                              "relative": False})):
        answer = sim.drive.apply(action, args)
        assert answer == "not enabled (Switch on disabled) - enable torque first", action
    sim.run(500)
    assert sim.drive.position_user == 0


def test_after_the_reset_with_ten_cmd_held_home_names_the_fresh_enable() -> None:
    sim = make_sim()
    sim.drive.apply("enable", {"on": True})
    sim.run(50)
    sim.drive.apply("inject_alarm", {"code": FOLLOWING_ERROR})
    sim.drive.apply("clear_alarm", {"code": FOLLOWING_ERROR})
    sim.run(500)
    sim.drive.apply("alarm_reset", {})
    sim.run(50)
    assert sim.drive.state is State.SWITCH_ON_DISABLED
    assert "R00 = 0, then 3" in sim.drive.apply("home", {})


def test_an_enabled_drive_answers_nothing() -> None:
    sim = make_sim()
    sim.drive.apply("enable", {"on": True})
    sim.run(50)
    assert sim.drive.apply("move", {"position": 100, "relative": False}) is None
    assert sim.drive.apply("start", {}) is None
    assert sim.drive.apply("home", {}) is None


def test_a_save_start_needs_no_torque() -> None:
    """Mode -50's start saves (ch. 2): no motion, so no answer about motion."""
    sim = make_sim()
    sim.drive.apply("set_mode", {"mode": -50})
    assert sim.drive.apply("start", {}) is None
