"""CN2 digital I/O with the bit numbers of seed 004 ch. 2 "I/O digitali" (repeated in ch. 4),
the position latch and its 2 ms filter, digital_out_mask, TEN and IEN."""

from __future__ import annotations

import pytest
from servo_helpers import make_sim

from devices.servo import ds402
from devices.servo.io import INPUTS, OUTPUTS

# (name, CN2 pin, bit in digital_inputs) as the ECO2 / ECO4 table prints them
INPUT_TABLE = [("start", 1, 1), ("in2", 2, 2), ("in3", 3, 3), ("in4", 4, 4), ("select", 5, 5),
               ("in6", 6, 6), ("in7", 7, 7), ("neg_limit", 8, 8), ("pos_limit", 9, 9),
               ("in11", 10, 11), ("latch", 11, 0), ("home", 14, 10)]
OUTPUT_TABLE = [("end_of_job", 12, 0), ("out1", 13, 1), ("near_target", 15, 3),
                ("brake", 16, 2)]


@pytest.mark.parametrize(("name", "pin", "bit"), INPUT_TABLE)
def test_input_bits(name: str, pin: int, bit: int) -> None:
    assert (INPUTS[name].pin, INPUTS[name].bit) == (pin, bit)
    sim = make_sim()
    sim.drive.apply("set_input", {"name": "home", "value": False})
    base = sim.drive.read_register(48)
    sim.drive.apply("set_input", {"name": name, "value": True})
    assert sim.drive.read_register(48) == base | 1 << bit
    assert sim.drive.od.read(0x60FD, 0) == base | 1 << bit


@pytest.mark.parametrize(("name", "pin", "bit"), OUTPUT_TABLE)
def test_output_mask_makes_a_pin_a_generic_output(name: str, pin: int, bit: int) -> None:
    """Mask bit 1: the pin follows digital_outputs (R50); 0: its primary function."""
    assert (OUTPUTS[name].pin, OUTPUTS[name].bit) == (pin, bit)
    sim = make_sim()
    assert not sim.drive.outputs()[name]
    sim.w(50, 1 << bit)
    assert not sim.drive.outputs()[name]  # not an output until the mask says so
    sim.w(49, 1 << bit)
    assert sim.drive.outputs()[name]
    assert sim.drive.od.read(0x60FE, 2) == 1 << bit
    sim.w(50, 0)
    assert not sim.drive.outputs()[name]


def test_brake_output_releases_in_torque() -> None:
    sim = make_sim()
    assert not sim.drive.outputs()["brake"]
    sim.w(0, 0x03)
    assert sim.drive.outputs()["brake"]


def test_the_carriage_actuates_the_switches() -> None:
    sim = make_sim()
    assert sim.drive.read_register(48) & (1 << 10)  # home switch (active from -3000 up)
    sim.w(1, 3)
    sim.w(13, -30000)
    sim.w(0, 0x03)
    sim.run_until(lambda: sim.drive.read_register(48) & (1 << 8), 5_000)
    assert sim.drive.snapshot()["limits"] == {"neg": True, "pos": False, "home": False}


def test_latch_captures_at_the_rising_edge_after_2_ms() -> None:
    """The input must stay high >= 2 ms; the capture is the position at the rising edge."""
    sim = make_sim()
    sim.w(1, 3)
    sim.w(13, 6000)
    sim.w(0, 0x03)
    sim.run(300)
    sim.drive.apply("set_input", {"name": "latch", "value": True})
    sim.run(1)
    at_edge = sim.drive.position_user
    assert sim.drive.statusword & ds402.SW_LATCH_INPUT
    sim.drive.apply("set_input", {"name": "latch", "value": False})  # a 1 ms glitch
    sim.run(5)
    assert not sim.drive.read_register(5) & 0x10
    sim.drive.apply("set_input", {"name": "latch", "value": True})
    at_edge = sim.drive.position_user
    sim.run(1)
    assert not sim.drive.read_register(5) & 0x10
    sim.run(2)
    assert sim.drive.read_register(5) & 0x10  # Ltc_st
    assert sim.drive.statusword & ds402.SW_LATCHED  # 0x6041 bit 14
    assert sim.drive.read_register(7) == at_edge
    assert sim.drive.od.read(0x2001, 0) == at_edge
    assert sim.drive.od.read(0x2004, 0) == at_edge  # fits 16 bits here
    sim.w(0, 0x13)  # Ltc_rst
    assert not sim.drive.read_register(5) & 0x10


def test_latch_flag_reset_by_0x6040_bit_14() -> None:
    sim = make_sim()
    sim.drive.apply("set_input", {"name": "latch", "value": True})
    sim.run(3)
    assert sim.drive.statusword & ds402.SW_LATCHED
    sim.cw(0x4000)
    assert not sim.drive.statusword & ds402.SW_LATCHED


def test_ien_low_stops_the_motion_and_keeps_torque() -> None:
    sim = make_sim()
    sim.w(1, 3)
    sim.w(13, 30000)
    sim.w(0, 0x03)
    sim.run(300)
    sim.drive.apply("set_input", {"name": "ien", "value": False})
    sim.run(1)
    assert sim.drive.read_register(5) & 0x07 == 0x05  # in torque, not enabled, stopping
    sim.run(500)
    assert sim.drive.read_register(8) == 0
    assert sim.drive.read_register(5) & 0x07 == 0x01
    sim.drive.apply("set_input", {"name": "ien", "value": True})
    sim.run(400)
    assert sim.drive.read_register(8) == 30000  # the velocity command is still there
