"""Alarm reset says why it changed nothing, and the snapshot names the injected causes.

Seed 004 ch. 5 "Reset allarmi": a reset clears the alarms whose cause is gone; "se la condizione
di allarme persiste" the drive stays in Fault. The panel's Alarm reset used to change nothing on
screen while only the drive log said so; the action's answer (as ``jog``'s) now says why, in
what the drive shows: the cause persists, never that it was injected (a trainee's page gets the
answer; the injected causes are the snapshot's ``injected``, an instructor's row).
"""

from __future__ import annotations

from servo_helpers import Sim, make_sim

from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State

FOLLOWING_ERROR = 16  # "asse rilasciato immediatamente": Fault at once
MOTOR_THERMAL = 2  # no action printed: the emergency ramp first


def _enabled(fieldbus: str = "modbus") -> Sim:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    sim.w(1, 3)
    sim.w(13, 30000)
    sim.drive.apply("enable", {"on": True})
    sim.run(300)
    assert sim.drive.state is State.OPERATION_ENABLED
    return sim


def test_a_reset_with_the_cause_still_there_says_it_persists() -> None:
    sim = _enabled()
    drive = sim.drive
    drive.apply("inject_alarm", {"code": str(FOLLOWING_ERROR)})
    sim.run(5)
    assert drive.state is State.FAULT
    assert drive.snapshot()["injected"] == [{"code": 16, "name": "FOLLOWING_ERROR"}]
    why = drive.apply("alarm_reset", {})
    assert why == "alarm 16 persists: the cause persists"
    sim.run(1)
    assert drive.state is State.FAULT
    assert f"alarm reset refused: {why}" in [e["text"] for e in sim.kinds("log")]  # the same
    drive.apply("clear_alarm", {"code": str(FOLLOWING_ERROR)})
    assert drive.snapshot()["injected"] == []
    assert drive.apply("alarm_reset", {}) is None  # the reset went through: nothing to say
    assert drive.state is not State.FAULT  # R00 still asks for torque: enabled again


def test_the_snapshot_lists_the_injected_causes_only() -> None:
    """A cause the model sees (not injected) is no instructor's secret: not in the list."""
    sim = make_sim()
    assert sim.drive.snapshot()["injected"] == []
    sim.drive.raise_alarm(9)  # a rejected flash image: an event, not injected
    assert sim.drive.snapshot()["injected"] == []


def test_a_reset_during_the_fault_reaction_says_to_wait_for_fault() -> None:
    sim = _enabled()
    drive = sim.drive
    drive.apply("inject_alarm", {"code": str(MOTOR_THERMAL)})
    drive.apply("clear_alarm", {"code": str(MOTOR_THERMAL)})
    sim.run(5)
    assert drive.state is State.FAULT_REACTION_ACTIVE
    why = drive.apply("alarm_reset", {})
    assert why == "alarm 2 still stopping the axis: reset in Fault"


def test_a_profinet_alarm_30_needs_a_power_cycle() -> None:
    """Ch. 6: 30-33 are not resettable; only a power cycle clears them."""
    sim = _enabled("profinet")
    drive = sim.drive
    drive.apply("inject_alarm", {"code": "30"})
    drive.apply("clear_alarm", {"code": "30"})
    sim.run_until(lambda: drive.state is State.FAULT, 2_000)
    why = drive.apply("alarm_reset", {})
    assert why == "alarm 30 is not resettable: switch the drive off and on"


def test_a_reset_with_no_alarm_says_nothing() -> None:
    sim = _enabled()
    assert sim.drive.apply("alarm_reset", {}) is None
