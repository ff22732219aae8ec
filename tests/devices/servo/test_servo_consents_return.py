"""TEN and IEN coming back with the commands held (docs/servo-drive.md §Two views, "Hardware
consents").

Seed 004 calls the two inputs consents ("Abilitazioni hardware. Consenso alla messa in coppia
dell'asse: segnale TEN a 24 Vdc. Consenso al movimento dell'asse: segnale IEN a 24 Vdc", ch. 4
l. 3654-3660) that a master keeps high and that "potranno ad esempio venire disattivati in
situazioni di emergenza"; Ten_cmd and Ien_cmd are levels ("1: asse in coppia", "1: abilitazione
movimentazioni", ch. 1), and 0x6041 bit 15 forces the target velocity to 0 while "segnale TEN
basso" or "segnale IEN basso" (ch. 4 l. 3123-3126). No alarm is raised and nothing is reset, so
the consent returning with the command held is enough: torque comes back with TEN, the level
commands (a speed, the interpolator, the electronic axis) run again with IEN, and an edge
(a positioner or homing start) is not replayed. The same model serves Modbus, CANopen and
EtherCAT (CoE); an alarm reset with Ten_cmd held still waits for a fresh Ten_cmd, TEN or not.
"""

from __future__ import annotations

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo import ds402
from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State

SPEED = 30000
FIELDBUSES = ("modbus", "canopen", "ethercat")


def _set(sim: Sim, name: str, value: bool) -> None:
    sim.drive.apply("set_input", {"name": name, "value": value})


def _running_in_mode_3(fieldbus: str) -> Sim:
    """Mode 3 at SPEED, written as each master writes it: R01 / R13 / R00 or 0x6060 / 0x60FF /
    the ch. 4 enable sequence."""
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    if fieldbus == "modbus":
        sim.w(1, 3)
        sim.w(13, SPEED)
        sim.w(0, 0x03)
    else:
        sim.drive.od.write(0x6060, 0, 3)
        sim.drive.od.write(0x60FF, 0, SPEED)
        sim.cw(*CANOPEN_ENABLE)
    sim.run(400)
    assert sim.drive.read_register(8) == SPEED
    return sim


@pytest.mark.parametrize("fieldbus", FIELDBUSES)
def test_ten_back_with_the_command_held_puts_torque_back(fieldbus: str) -> None:
    sim = _running_in_mode_3(fieldbus)
    _set(sim, "ten", False)
    sim.run(1)
    assert sim.drive.state is State.SWITCHED_ON  # transition 5: torque off, the axis coasts
    assert not sim.r05 & 0x01  # Ten_st
    assert sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO
    sim.run_until(lambda: sim.drive.plant.omega == 0.0, 5_000)
    assert sim.drive.state is State.SWITCHED_ON  # no alarm, no Fault: nothing to reset
    _set(sim, "ten", True)
    sim.run(1)
    assert sim.drive.state is State.OPERATION_ENABLED  # transition 4 on the held command
    assert sim.r05 & 0x03 == 0x03
    sim.run(400)
    assert sim.drive.read_register(8) == SPEED  # the speed command is still there


@pytest.mark.parametrize("fieldbus", FIELDBUSES)
def test_ien_back_with_ien_cmd_held_runs_the_speed_again(fieldbus: str) -> None:
    sim = _running_in_mode_3(fieldbus)
    _set(sim, "ien", False)
    sim.run(500)
    assert sim.drive.state is State.OPERATION_ENABLED  # held in torque, standing
    assert sim.drive.read_register(8) == 0
    assert sim.r05 & 0x03 == 0x01  # Ten_st, no Ien_st
    assert sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO
    _set(sim, "ien", True)
    sim.run(400)
    assert sim.r05 & 0x03 == 0x03
    assert not sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO
    assert sim.drive.read_register(8) == SPEED


def test_ien_back_does_not_replay_a_positioner_start() -> None:
    """Pos_str is an edge ("0 -> 1: start nuovo posizionamento", ch. 1): the move IEN stopped
    is over; the axis stands in torque until the master's next start."""
    sim = make_sim()
    sim.w(9, 3000)  # 3 s at R12 = 1000
    sim.w(0, 0x03)
    sim.w(0, 0x23)
    sim.run(300)
    _set(sim, "ien", False)
    sim.run(1000)
    stopped_at = sim.drive.position_user
    assert 0 < stopped_at < 3000
    _set(sim, "ien", True)
    sim.run(1000)
    assert sim.drive.position_user == stopped_at
    assert sim.drive.read_register(8) == 0
    assert sim.r05 & 0x20  # sp_rdy: a start now is taken
    sim.w(0, 0x23)
    sim.run_until(lambda: sim.r05 & 0x40, 5_000)  # End of Job
    assert abs(sim.drive.position_user - 3000) < 10


@pytest.mark.parametrize("fieldbus", ("modbus", "canopen"))
def test_an_axis_released_by_an_alarm_stays_released_when_ten_comes_back(fieldbus: str) -> None:
    """TEN returning is no enable command: after the reset of "Asse rilasciato immediatamente"
    the register view still wants Ten_cmd 0 -> 1 (docs "Re-enabling after an alarm"), the
    CiA 402 view 6, 7, F."""
    sim = _running_in_mode_3(fieldbus)
    sim.drive.apply("inject_alarm", {"code": 16})
    sim.drive.apply("clear_alarm", {"code": 16})
    sim.run_until(lambda: sim.drive.plant.omega == 0.0, 5_000)
    if fieldbus == "modbus":
        sim.w(0, 0x0B)
        sim.w(0, 0x03)
    else:
        sim.cw(0x008F, 0x000F)
    assert sim.drive.state is State.SWITCH_ON_DISABLED
    _set(sim, "ten", False)
    sim.run(10)
    _set(sim, "ten", True)
    sim.run(300)
    assert sim.drive.state is State.SWITCH_ON_DISABLED
    assert sim.drive.read_register(8) == 0


def test_ien_back_engages_the_electronic_axis_again() -> None:
    """Mode -2 follows the master while Start is high and the start bit is 1 ("1: start, asse
    slave in asse col master", ch. 1; ch. 2 "Questa avviene se il segnale è a livello alto ed
    il bit 5 di ControlWord è a 1"): levels, so IEN back with both held engages it again."""
    sim = make_sim()
    sim.w(25, 2)
    sim.w(1, -2)
    sim.drive.apply("master_encoder", {"rpm": 300.0})
    _set(sim, "start", True)
    sim.w(0, 0x43)
    sim.run(200)
    assert sim.drive.read_register(73) == 600 and sim.r05 & 0x40
    _set(sim, "ien", False)
    sim.run(500)
    assert sim.drive.read_register(73) == 0 and not sim.r05 & 0x40
    _set(sim, "ien", True)
    sim.run(200)
    assert sim.drive.read_register(73) == 600 and sim.r05 & 0x40
    assert sim.drive.read_register(46) == 0


def test_the_ch4_enable_sequence_run_while_ten_is_low_waits_for_ten() -> None:
    """Ch. 4's "necessaria solamente se l'asse non è in coppia" (l. 3455): a CiA 402 master
    that runs 0, 0x80, 0, 6, 7, 0xF after TEN dropped reaches Switched on; TEN back is the
    rest (transition 4)."""
    sim = _running_in_mode_3("canopen")
    _set(sim, "ten", False)
    sim.run(1)
    sim.cw(*CANOPEN_ENABLE)
    sim.run(10)
    assert sim.drive.state is State.SWITCHED_ON
    _set(sim, "ten", True)
    sim.run(1)
    assert sim.drive.state is State.OPERATION_ENABLED


def test_the_jog_notice_names_the_consent_that_is_low() -> None:
    """The panel's Enable writes R00 = 3, which a held Ten_cmd already is: with TEN low the
    notice sends the trainee to the input, and says whether the command is still there."""
    sim = make_sim()
    d = sim.drive
    _set(sim, "ten", False)
    sim.run(1)
    assert d.motion_blocked() == \
        "not enabled (Switch on disabled, TEN input low) - switch TEN on and enable torque"
    d.apply("enable", {"on": True})
    sim.run(1)
    assert d.state is State.SWITCHED_ON
    assert d.apply("jog", {"direction": 1}) == \
        "no torque (TEN input low) - switch TEN on: the enable is held, torque comes back with it"
    _set(sim, "ten", True)
    sim.run(1)
    assert d.motion_blocked() is None
    _set(sim, "ien", False)
    assert d.motion_blocked() == \
        "motion not enabled (IEN input low) - switch IEN on: motion resumes with it"
    _set(sim, "ien", True)
    sim.w(0, 0x01)  # Ten_cmd only
    assert d.motion_blocked() == "motion not enabled (Ien_cmd off, R00 bit 1) - Enable sets it"
