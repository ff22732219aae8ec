"""One state, two views: the register-mode R00 / R05 (seed 004 ch. 1 quick reference) and the
CiA 402 0x6040 / 0x6041 (ch. 4) always describe the same drive."""

from __future__ import annotations

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo import control, ds402
from devices.servo.control import StatusFlags, cia402_status, register_status
from devices.servo.ds402 import State

MODES = (1, 3, 6, 7, -1, -2, -50, -127)


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("r00", [0x00, 0x03, 0x08, 0x04, 0x13, 0x23, 0x43, 0x63, 0xA3, 0xE3])
def test_register_control_word_round_trip(mode: int, r00: int) -> None:
    """R00 -> 0x6040 -> R00 keeps every bit the mode defines (Ien_cmd rides along)."""
    cw = control.controlword_from_register(r00, mode)
    back = control.register_from_controlword(cw, mode, ien_cmd=bool(r00 & control.IEN_CMD))
    defined = 0x1F | sum(1 << b for b in control.control_bit_names(mode) if b >= 5)
    if mode in control.ELECTRONIC_AXIS:  # bit 5 (I/O chapter) or 6 (quick reference) starts
        defined &= ~(control.BIT5 | control.BIT6)
        assert bool(back & control.BIT6) == bool(r00 & (control.BIT5 | control.BIT6))
    if mode in control.SAVE_LOAD:
        defined &= ~(control.BIT5 | control.BIT6)  # Save / Load have no 0x6040 image
    if not r00 & control.TEN_CMD:
        defined &= ~control.IEN_CMD  # without torque Ien_cmd has no CiA 402 image
    assert back & defined == r00 & defined


@pytest.mark.parametrize(("mode", "r00", "cw"), [
    (1, 0x03, 0x000F), (1, 0x23, 0x001F), (1, 0x63, 0x003F), (1, 0xA3, 0x005F),
    (6, 0x43, 0x001F), (7, 0x23, 0x001F), (-2, 0x43, 0x080F), (1, 0x08, 0x0080),
    (1, 0x07, 0x010F), (1, 0x13, 0x400F), (-50, 0x20, 0x0000)])
def test_register_to_cia402_examples(mode: int, r00: int, cw: int) -> None:
    """0x23 starts positioning like 0x001F, 0x43 homing like 0x001F (ch. 2 vs ch. 4 examples)."""
    assert control.controlword_from_register(r00, mode) == cw


@pytest.mark.parametrize("state", list(State))
@pytest.mark.parametrize("mode", MODES)
def test_status_words_agree_on_common_bits(state: State, mode: int) -> None:
    flags = StatusFlags(state=state, mode=mode, motion_enabled=state is State.OPERATION_ENABLED,
                        latched=True, end_of_job=True, homing_attained=True, ip_active=True)
    r05, sw = register_status(flags), cia402_status(flags)
    assert bool(r05 & 0x01) == state.in_torque
    assert bool(r05 & 0x08) == bool(sw & 0x08)  # Alm_st <-> fault (and fault reaction)
    assert bool(r05 & 0x10) == bool(sw & ds402.SW_LATCHED)
    assert ds402.state_of(sw) is state
    if mode == 6:
        assert bool(r05 & 0x40) == bool(sw & ds402.SW_MODE_12)  # Homing ok <-> attained


def _views(sim: Sim) -> tuple[int, int, int, int]:
    d = sim.drive
    return d.read_register(0), d.read_register(5), d.od.read(0x6040, 0), d.od.read(0x6041, 0)


def _check_agree(sim: Sim) -> None:
    r00, r05, cw, sw = _views(sim)
    state = ds402.state_of(sw)
    assert state is sim.drive.state
    assert bool(r05 & 0x01) == state.in_torque
    assert bool(r05 & 0x08) == (state in (State.FAULT, State.FAULT_REACTION_ACTIVE))
    assert bool(r00 & control.TEN_CMD) == (cw & 0x0F == 0x0F)
    assert bool(r00 & control.ALM_RST) == bool(cw & ds402.CW_FAULT_RESET)
    assert bool(r00 & control.STP_CMD) == bool(cw & ds402.CW_HALT)
    # bit 15 follows the consents TEN, IEN and Ien_cmd (ch. 4), Ien_st needs them too (ch. 1)
    d = sim.drive
    consents = d.ien_cmd and d.input_level("ten") and d.input_level("ien")
    assert bool(sw & ds402.SW_VELOCITY_FORCED_ZERO) is not consents
    assert not (r05 & 0x02 and sw & ds402.SW_VELOCITY_FORCED_ZERO)


def test_views_agree_through_a_session() -> None:
    """Alternate masters: Modbus register writes and CiA 402 writes on the same drive."""
    sim = make_sim()
    _check_agree(sim)
    sim.w(0, 0x03)
    _check_agree(sim)
    sim.cw(0x0002)
    sim.run(10)
    _check_agree(sim)
    sim.cw(*CANOPEN_ENABLE)
    _check_agree(sim)
    assert sim.drive.read_register(0) == 0x03
    sim.w(0, 0x07)  # Stp_cmd = halt
    _check_agree(sim)
    sim.drive.apply("inject_alarm", {"code": 3})
    _check_agree(sim)
    sim.drive.apply("clear_alarm", {"code": 3})
    sim.w(0, 0x08)
    _check_agree(sim)
    sim.drive.apply("set_input", {"name": "ien", "value": False})
    sim.w(0, 0x03)
    _check_agree(sim)
    assert sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO  # IEN low (ch. 4 bit 15)
    assert sim.drive.read_register(5) & 0x03 == 0x01  # in torque, motions not enabled


def test_ien_cmd_off_keeps_torque_without_motion() -> None:
    """R00 = 1: Ten_cmd only. In torque (Ten_st) but Ien_st = 0; 0x6041 bit 15 set."""
    sim = make_sim()
    sim.w(0, 0x01)
    assert sim.drive.state is State.OPERATION_ENABLED
    assert sim.drive.read_register(5) & 0x03 == 0x01
    assert sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO


def test_hardware_ten_low_removes_torque_and_returns_with_it() -> None:
    """TEN is the torque consent: low -> transition 5; back high with Ten_cmd held -> 4."""
    sim = make_sim()
    sim.w(0, 0x03)
    sim.drive.apply("set_input", {"name": "ten", "value": False})
    assert sim.drive.state is State.SWITCHED_ON
    assert sim.drive.read_register(5) & 0x01 == 0
    sim.run(5)
    assert sim.drive.state is State.SWITCHED_ON
    sim.drive.apply("set_input", {"name": "ten", "value": True})
    sim.run(1)
    assert sim.drive.state is State.OPERATION_ENABLED


def _homed_with_r00_0x43(sim: Sim) -> None:
    """Mode 6, R00 = 3 then 0x43 (ch. 2 example), homing method 35: R00 keeps bit 6."""
    sim.w(2, 60)
    sim.w(18, 35)
    sim.w(1, 6)
    sim.w(0, 0x03)
    sim.w(0, 0x43)
    sim.run_until(lambda: sim.r05 & 0x40, 3_000)  # Homing ok
    assert sim.drive.read_register(0) == 0x43


def test_after_a_mode_change_r00_bit_5_starts_the_positioner() -> None:
    """R00's bits 5-7 are "specifico del modo selezionato" (ch. 1): after homing with 0x43 and
    mode 1, R00 reads Pos_str = 0, so 0x23 is Pos_str 0 -> 1, "start nuovo posizionamento".
    The drive kept homing's 0x6040 image (bit 4 set) and took 0x23 as no edge."""
    sim = make_sim()
    _homed_with_r00_0x43(sim)
    sim.w(1, 1)
    sim.w(9, 600)
    sim.w(0, 0x23)
    sim.run_until(lambda: sim.r05 & 0x40, 3_000)  # End of Job
    assert sim.drive.position_user == 600


def test_after_a_mode_change_the_interpolator_follows_r00_bit_5() -> None:
    """Mode 7 entered with R00 = 0x43: Ip_str (bit 5) is 0, so the interpolator is not active
    (R05 bit 5 Ip_st, 0x6041 bit 12); it starts with R00 bit 5."""
    sim = make_sim()
    _homed_with_r00_0x43(sim)
    sim.w(1, 7)
    sim.run(5)
    assert not sim.r05 & 0x20
    assert not sim.drive.statusword & ds402.SW_MODE_12
    sim.w(0, 0x23)
    sim.run(5)
    assert sim.r05 & 0x20


def test_after_a_mode_change_r00_bit_6_engages_the_electronic_axis() -> None:
    """Mode -2 entered with R00 = 0x43: bit 6 "1: start, asse slave in asse col master" with the
    Start input high (ch. 1, ch. 2 "I/O digitali") engages the axis (R05 bit 6)."""
    sim = make_sim()
    _homed_with_r00_0x43(sim)
    sim.drive.apply("set_input", {"name": "start", "value": True})
    sim.drive.apply("master_encoder", {"rpm": 60.0})
    sim.w(1, -2)
    sim.run(200)
    assert sim.r05 & 0x40
    assert sim.drive.velocity_user > 0


def test_after_a_mode_change_r00_reads_the_cia402_master_s_command_in_the_new_mode() -> None:
    """A CiA 402 master's 0x001F starts homing in mode 6 (R00 bit 6); in mode 1 the same
    0x6040 bit 4 is the new set-point, R00 bit 5: the register view follows the mode."""
    sim = make_sim()
    sim.w(18, 35)
    sim.cw(*CANOPEN_ENABLE)
    sim.drive.set_mode(6)
    sim.cw(0x001F)
    assert sim.drive.read_register(0) & 0xE0 == 0x40
    sim.drive.set_mode(1)
    assert sim.drive.read_register(0) & 0xE0 == 0x20
    assert sim.drive.cw == 0x001F  # DSP 402: the master's bits stay as written
