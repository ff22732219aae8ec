"""Torque after an alarm reset: the master enables again, the drive does not (docs/servo-drive.md
"Re-enabling after an alarm").

Seed 004 writes every reset with the enable off: ch. 2 "Si resettano quindi eventuali allarmi
presenti scrivendo nel registro 0x8000 (ControlWord) il valore 8", then "il valore 3"; ch. 6
"scrivendo il codice 0x08 nella Control Word"; ch. 4 / ch. 5 0x80 on 0x6040 inside the enable
sequence 0, 0x80, 0, 6, 7, 0xF (DSP 402 transition 15 ends in Switch on disabled). Ch. 3's
"Azione: Asse rilasciato immediatamente" releases the axis and no line brings it back by itself.
A register master that resets with Ten_cmd held (R00 = 0x0B, then 3) therefore finds the axis
released until it writes Ten_cmd 0 -> 1; before, the drive went back into torque at once and in
mode 3 ran off at R13.
"""

from __future__ import annotations

from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State

FOLLOWING_ERROR = 16  # "Asse rilasciato immediatamente"
SPEED = 30000


def _at_speed(sim: Sim) -> bool:
    return abs(sim.drive.velocity_user - SPEED) < SPEED / 50


def _running_in_mode_3(fieldbus: str = "modbus") -> Sim:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    sim.w(1, 3)
    sim.w(13, SPEED)
    if fieldbus == "modbus":
        sim.w(0, 0x03)
    else:
        sim.cw(*CANOPEN_ENABLE)
    sim.run(300)
    assert _at_speed(sim)
    return sim


def _alarm_gone(sim: Sim) -> None:
    """Alarm 16, its cause removed: the drive in Fault, the axis released and standing."""
    drive = sim.drive
    drive.apply("inject_alarm", {"code": FOLLOWING_ERROR})
    drive.apply("clear_alarm", {"code": FOLLOWING_ERROR})
    sim.run_until(lambda: drive.plant.omega == 0.0, 5_000)
    assert drive.state is State.FAULT


def _released(sim: Sim) -> None:
    sim.run(300)
    assert sim.drive.read_register(46) == 0
    assert sim.drive.state is State.SWITCH_ON_DISABLED
    assert not sim.r05 & 0x01  # Ten_st
    assert sim.drive.velocity_user == 0


def test_a_reset_with_ten_cmd_held_leaves_the_axis_released() -> None:
    sim = _running_in_mode_3()
    _alarm_gone(sim)
    sim.w(0, 0x0B)  # Alm_rst with Ten_cmd and Ien_cmd held
    sim.w(0, 0x03)
    _released(sim)
    sim.w(0, 0x03)  # the same level again is no enable
    _released(sim)
    sim.w(0, 0x00)
    sim.w(0, 0x03)  # Ten_cmd 0 -> 1: torque, and mode 3 runs at R13 as commanded
    sim.run(300)
    assert sim.drive.state is State.OPERATION_ENABLED
    assert _at_speed(sim)


def test_the_panel_s_reset_pulse_leaves_the_axis_released_until_enable() -> None:
    sim = _running_in_mode_3()
    _alarm_gone(sim)
    assert sim.drive.apply("alarm_reset", {}) is None
    _released(sim)
    assert "R00 = 0, then 3" in (sim.drive.motion_blocked() or "")
    sim.drive.apply("enable", {"on": True})  # the panel's Enable is a fresh Ten_cmd
    sim.run(300)
    assert sim.drive.state is State.OPERATION_ENABLED
    assert _at_speed(sim)


def test_the_seed_s_reset_with_8_then_3_enables_as_before() -> None:
    """Ch. 2 / ch. 6: 8 resets (Ten_cmd low), 3 is the enable."""
    sim = _running_in_mode_3()
    _alarm_gone(sim)
    sim.w(0, 0x08)
    _released(sim)
    sim.w(0, 0x03)
    sim.run(300)
    assert sim.drive.state is State.OPERATION_ENABLED


def test_a_cia402_master_needs_its_enable_sequence_again() -> None:
    """DSP 402 transition 15 ends in Switch on disabled, where 0x000F commands nothing."""
    sim = _running_in_mode_3("canopen")
    _alarm_gone(sim)
    sim.cw(0x008F, 0x000F)
    _released(sim)
    sim.cw(0x0006, 0x0007, 0x000F)
    sim.run(300)
    assert sim.drive.state is State.OPERATION_ENABLED
