"""A save runs with the IEN input low (seed 004 ch. 4 "Salvataggio su flash": "il salvataggio è
possibile solo se il motore non è abilitato (segnali IEN e/o TEN disabilitati)"): IEN low is
"motion not enabled" (ch. 1 Ien_st), the axis held in torque; docs/servo-drive.md §Flash."""

from __future__ import annotations

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo import flashsave
from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State

SAVE_MS = flashsave.SAVE_DURATION_US / 1000


def _ien(sim: Sim, on: bool) -> None:
    sim.drive.apply("set_input", {"name": "ien", "value": on})


def _in_torque_ien_low(fieldbus: str = "modbus") -> Sim:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    if fieldbus == "modbus":
        sim.w(0, 0x03)
    else:
        sim.cw(*CANOPEN_ENABLE)
    sim.run(10)
    _ien(sim, False)
    sim.run(10)
    assert sim.drive.state is State.OPERATION_ENABLED
    assert not sim.drive.read_register(5) & 0x02  # Ien_st = 0
    return sim


@pytest.mark.parametrize(("fieldbus", "trigger"), [
    ("modbus", "0x3802"), ("canopen", "0x1010"), ("ethercat", "0x2007")])
def test_a_save_runs_with_ien_low_and_ten_high(fieldbus: str, trigger: str) -> None:
    """A review's run: a save asked with IEN low in torque used to wait for ever."""
    sim = _in_torque_ien_low(fieldbus)
    drive = sim.drive
    if trigger == "0x3802":
        drive.write_parameter(0x3802, 0x11)
    elif trigger == "0x1010":
        drive.od.write(0x1010, 1, 0x65766173)
    else:
        drive.od.write(0x2007, 0, 0x11)
    assert drive.saving
    assert drive.display == "--"
    took = sim.run_until(lambda: drive.responding, 10_000)
    assert took == pytest.approx(SAVE_MS, abs=2)
    assert sim.flash.writes == 1 and drive.save_done
    assert drive.state is State.OPERATION_ENABLED  # torque stayed on (Ten_st)


def test_a_save_asked_in_torque_runs_when_ien_goes_low() -> None:
    sim = make_sim()
    sim.w(0, 0x03)
    sim.drive.apply("save", {})
    sim.run(100)
    assert not sim.drive.saving and sim.drive.save_pending
    _ien(sim, False)
    sim.run(1)
    assert sim.drive.saving
    sim.run_until(lambda: sim.drive.responding, 10_000)
    assert sim.flash.writes == 1


def test_ien_cmd_off_alone_does_not_let_a_save_run() -> None:
    """The seed names the signals IEN / TEN; R00 = 1 (Ten_cmd, no Ien_cmd) keeps it waiting."""
    sim = make_sim()
    sim.w(0, 0x01)
    sim.drive.apply("save", {})
    sim.run(5_000)
    assert sim.flash.writes == 0 and sim.drive.save_pending


def test_no_motion_until_the_save_is_over_when_ien_returns() -> None:
    sim = _in_torque_ien_low()
    drive = sim.drive
    sim.w(1, 3)
    sim.w(13, 30000)
    drive.apply("save", {})
    assert drive.saving
    sim.run(100)
    _ien(sim, True)
    sim.run(1_000)
    assert drive.saving and drive.velocity_user == 0
    assert not drive.motion_enabled  # Ien_st stays 0 while the drive saves
    sim.run_until(lambda: drive.responding, 10_000)
    sim.run(500)
    assert drive.velocity_user > 0  # the jog goes on once the save is done


def test_ten_low_during_such_a_save_still_takes_the_torque_off() -> None:
    """TEN is the hardware consent: transition 5 also while the drive saves."""
    sim = _in_torque_ien_low()
    sim.drive.apply("save", {})
    sim.run(100)
    assert sim.drive.saving and sim.drive.state is State.OPERATION_ENABLED
    sim.drive.apply("set_input", {"name": "ten", "value": False})
    sim.run(1)
    assert sim.drive.state is State.SWITCHED_ON
    assert sim.drive.saving  # the save goes on
    sim.run_until(lambda: sim.drive.responding, 10_000)
    assert sim.flash.writes == 1
