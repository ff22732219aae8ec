"""The seed's Modbus worked examples (seed 004 ch. 2 "Esempi"), replayed at model level.

Register numbers and values are those of the frames; the Modbus framing itself is tested on
the server side (app/modbus). Node 5 and node 1 are two drives of the examples.
"""

from __future__ import annotations

from servo_helpers import make_sim

from devices.servo.drive import DriveConfig

ENABLE, END_OF_JOB = 0x03, 0x40


def test_read_d1_d2_d3_node_5() -> None:
    """05 03 00 01 00 03 -> 05 03 06 00 14 00 32 00 32: d1 = 20, d2 = 50, d3 = 50."""
    sim = make_sim(DriveConfig(node_id=5))
    assert sim.drive.node_id == 5
    assert [sim.drive.read_parameter(a) for a in (1, 2, 3)] == [0x0014, 0x0032, 0x0032]


def test_write_d3_10() -> None:
    """05 06 00 03 00 0A: d3 = 10, read back 10."""
    sim = make_sim(DriveConfig(node_id=5))
    sim.drive.write_parameter(0x0003, 0x000A)
    assert sim.drive.read_parameter(3) == 10


def test_write_target_position_1000() -> None:
    """05 10 80 09 00 02 04 00 00 03 E8: R09 target_position = 1000."""
    sim = make_sim(DriveConfig(node_id=5))
    sim.drive.write_register(0x8009 - 0x8000, 0x0000_03E8)
    assert sim.drive.read_register(9) == 1000


def test_positioner_setup_homing_and_point_to_point_move() -> None:
    """Ch. 2 "Esempio di configurazione dell'asse in modalità posizionatore", node 01."""
    sim = make_sim()
    for address, value in ((0x8002, 0x003C), (0x800A, 0x0064), (0x800B, 0x0064),
                           (0x800C, 0x03E8), (0x801B, 0x0000), (0x8012, 0x0021),
                           (0x8013, 0x0000), (0x8015, 0x000A), (0x8016, 0x0064)):
        sim.w(address - 0x8000, value)
    sim.w(0, 0x08)  # reset alarms
    sim.w(1, 0x06)  # homing
    sim.w(0, 0x03)  # torque and motion enabled
    assert sim.drive.state.label == "Operation enabled"
    sim.w(0, 0x43)  # start homing
    sim.run_until(lambda: sim.r05 & END_OF_JOB, timeout_ms=10_000)  # "Homing ok"
    assert sim.drive.read_register(6) == 0  # home offset 0: the marker reads 0
    sim.w(0, 0x00)  # remove torque
    assert sim.r05 & ENABLE == 0
    sim.w(1, 0x01)  # positioner
    sim.w(9, 0x1770)
    sim.w(0, 0x03)
    sim.w(0, 0x23)  # start positioning
    assert sim.r05 & END_OF_JOB == 0  # End of Job drops at the start
    sim.run_until(lambda: sim.r05 & END_OF_JOB, timeout_ms=20_000)
    sim.run(20)
    assert sim.drive.read_register(6) == 6000
    assert sim.drive.outputs()["end_of_job"]
    assert sim.drive.read_register(0) == 0x03  # Pos_str returned to 0 by itself


def test_save_method_1_mode_minus_50_and_control_word_0x20() -> None:
    """01 10 80 01 00 02 04 FF FF FF CE (mode -50), then 01 10 80 00 ... 00 00 00 20."""
    sim = make_sim()
    sim.w(2, 0x3C)
    sim.w(1, 0xFFFF_FFCE)
    assert sim.drive.read_register(1) == -50
    sim.w(0, 0x20)
    assert sim.drive.saving and not sim.drive.responding
    sim.run_until(lambda: sim.drive.responding, timeout_ms=5_000)  # "tipicamente < 5 s"
    assert sim.r05 & 0x20  # save done
    assert b'"R02": 60' in sim.flash.data


def test_save_method_2_0x3802() -> None:
    """05 06 38 02 00 11 (and the 32-bit form 05 10 38 02 00 02 04 00 00 00 11)."""
    sim = make_sim(DriveConfig(node_id=5))
    sim.drive.write_parameter(3, 10)
    sim.drive.write_parameter(0x3802, 0x0011)
    assert not sim.drive.responding
    sim.run_until(lambda: sim.drive.responding, timeout_ms=5_000)
    sim.drive.write_save_command(0x0000_0011)
    assert sim.drive.saving
    assert b'"d3": 10' in sim.flash.data
