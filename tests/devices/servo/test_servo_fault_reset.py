"""Alarm reset acts in Fault only (seed 004 ch. 4 "Device Profile: DSP 402", transition 15;
ch. 5 "Reset allarmi"): a reset while the fault reaction still stops the axis changes nothing,
whichever way it comes (R00 bit 3, 0x6040 bit 7, the panel's Alarm reset)."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State

MOTOR_THERMAL = 2  # no action printed (ch. 3): the axis stops on the emergency ramp first


def _register_reset(sim: Sim) -> None:
    sim.drive.write_register(0, 0x0B)  # Alm_rst with Ten_cmd and Ien_cmd held
    sim.drive.write_register(0, 0x03)


def _controlword_reset(sim: Sim) -> None:
    sim.drive.write_controlword(0x008F)
    sim.drive.write_controlword(0x000F)


def _panel_reset(sim: Sim) -> None:
    sim.drive.apply("alarm_reset", {})


def _running(fieldbus: str) -> Sim:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    sim.w(1, 3)
    sim.w(13, 30000)
    if fieldbus == "modbus":
        sim.w(0, 0x03)
    else:
        sim.cw(*CANOPEN_ENABLE)
    sim.run(300)
    assert sim.drive.state is State.OPERATION_ENABLED
    return sim


@pytest.mark.parametrize(("fieldbus", "reset"), [
    ("modbus", _register_reset), ("canopen", _controlword_reset),
    ("ethercat", _controlword_reset), ("modbus", _panel_reset), ("canopen", _panel_reset)])
def test_a_reset_during_the_fault_reaction_changes_nothing(
        fieldbus: str, reset: Callable[[Sim], None]) -> None:
    sim = _running(fieldbus)
    drive = sim.drive
    drive.apply("inject_alarm", {"code": MOTOR_THERMAL})
    drive.apply("clear_alarm", {"code": MOTOR_THERMAL})  # the cause is gone: resettable
    sim.run(5)
    assert drive.state is State.FAULT_REACTION_ACTIVE
    reset(sim)
    sim.run(1)
    assert drive.state is State.FAULT_REACTION_ACTIVE
    assert drive.read_register(46) == MOTOR_THERMAL
    assert drive.error_code() == 0x7120
    assert drive.display == " 2"
    assert [e["active"] for e in sim.kinds("alarm")] == [True]
    sim.run_until(lambda: drive.state is State.FAULT, 2_000)
    assert drive.read_register(46) == MOTOR_THERMAL  # still shown in Fault, with its code
    assert drive.display == " 2"
    reset(sim)  # in Fault the same reset clears it (transition 15)
    sim.run(5)
    assert drive.read_register(46) == 0
    assert drive.state is not State.FAULT
    assert [e["active"] for e in sim.kinds("alarm")] == [True, False]


def test_the_reviewers_run_into_ls1_keeps_alarm_20_until_fault() -> None:
    """A review's run: R01 = 3, R13 = -150000, R00 = 3, run into LS1, reset at once."""
    sim = make_sim()
    sim.run_into_ls1()
    assert sim.drive.state is State.FAULT_REACTION_ACTIVE
    sim.w(0, 0x0B)
    sim.w(0, 0x03)
    sim.run(500)
    assert sim.drive.state is State.FAULT
    assert sim.drive.read_register(46) == 20
    assert sim.drive.display == "20"
