"""Pos_str, R00 bit 5 in the positioner: "0 -> 1: start nuovo posizionamento" (seed 004 ch. 1)
and "il bit ritorna automaticamente a zero" (ch. 2 "I/O digitali").

The bit returns to zero whether or not the drive could start: a start written while the motion
is not enabled (IEN input low, Ien_cmd off, Stp_cmd held) is consumed, and the master's next
Pos_str is a fresh 0 -> 1 edge that starts the move.
"""

from __future__ import annotations

import pytest
from servo_helpers import Sim, make_sim

from devices.servo import ds402

EOJ = 0x40


def _positioner(sim: Sim, target: int = 1000) -> None:
    sim.w(2, 60)
    sim.w(1, 1)
    sim.w(9, target)


@pytest.mark.parametrize("blocked, enabled", [
    (0x21, 0x23),  # Ien_cmd off
    (0x27, 0x23),  # Stp_cmd held
    (0x20, 0x23),  # no torque at all
], ids=["ien_cmd_off", "stp_cmd_held", "no_torque"])
def test_a_refused_start_clears_pos_str_and_the_next_one_starts(blocked: int,
                                                                 enabled: int) -> None:
    sim = make_sim()
    _positioner(sim)
    sim.w(0, blocked & ~0x20)
    sim.w(0, blocked)
    assert sim.drive.read_register(0) == blocked & ~0x20  # back to zero by itself
    assert sim.drive.position_user == 0
    sim.w(0, enabled)
    assert sim.drive.read_register(0) == enabled & ~0x20
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == 1000


def test_a_start_while_the_ien_input_is_low_is_consumed() -> None:
    """IEN low (the hardware consent): 0x23 does nothing and reads back 0x03; with IEN back,
    0x23 again starts the move."""
    sim = make_sim()
    _positioner(sim)
    sim.drive.apply("set_input", {"name": "ien", "value": False})
    sim.w(0, 0x03)
    sim.w(0, 0x23)
    assert sim.drive.read_register(0) == 0x03
    sim.run(100)
    assert sim.drive.position_user == 0
    sim.drive.apply("set_input", {"name": "ien", "value": True})
    sim.w(0, 0x23)
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == 1000


def test_a_cia402_master_keeps_its_new_set_point_bit() -> None:
    """0x6040 bit 4 is the DSP 402 handshake: the master clears it, not the drive (ch. 4)."""
    sim = make_sim()
    _positioner(sim)
    sim.drive.apply("set_input", {"name": "ien", "value": False})
    sim.cw(0x0006, 0x0007, 0x000F, 0x001F)
    assert sim.drive.cw & ds402.CW_NEW_SET_POINT


SP_RDY = 0x20


@pytest.mark.parametrize("r00, ien", [
    (0x00, True),  # fresh drive, no torque
    (0x01, True),  # in torque, Ien_cmd off
    (0x07, True),  # Stp_cmd held
    (0x03, False),  # the IEN input low
], ids=["no_torque", "ien_cmd_off", "stp_cmd_held", "ien_input_low"])
def test_sp_rdy_is_low_while_a_start_would_be_lost(r00: int, ien: bool) -> None:
    """sp_rdy "1: pronto per un nuovo set-point" (ch. 1, R05 bit 5): a drive that consumes a
    Pos_str without moving is not ready for one, so a PLC that waits for sp_rdy before its
    0x23 never loses the start (docs/servo-drive.md "sp_rdy")."""
    sim = make_sim()
    _positioner(sim)
    sim.drive.apply("set_input", {"name": "ien", "value": ien})
    sim.w(0, r00)
    assert not sim.r05 & SP_RDY
    sim.drive.apply("set_input", {"name": "ien", "value": True})
    sim.w(0, 0x03)
    assert sim.r05 & SP_RDY
    sim.w(0, 0x23)  # the start the PLC sends once sp_rdy is up: it is taken
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == 1000


def test_a_fresh_drive_reads_r05_0_and_an_alarm_drops_sp_rdy() -> None:
    sim = make_sim()
    sim.run(100)
    assert sim.r05 == 0x00  # mode 1, no torque: not ready for a set-point
    _positioner(sim)
    sim.w(0, 0x03)
    assert sim.r05 & SP_RDY
    sim.drive.apply("inject_alarm", {"code": "16"})
    sim.run(200)
    assert sim.r05 & 0x08 and not sim.r05 & SP_RDY
