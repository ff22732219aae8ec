"""Save to flash (seed 004 ch. 2, ch. 4 "Salvataggio", ch. 5 0x2007), power-up latching of c7
and c9, the 7-segment display during a save."""

from __future__ import annotations

import pytest
from servo_helpers import CANOPEN_ENABLE, make_sim

from devices.flash import MemoryFlash
from devices.servo import flashsave
from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State
from devices.servo.errors import AccessError


@pytest.mark.parametrize("trigger", ["mode-50", "0x3802", "0x1010", "0x2007", "action"])
def test_every_trigger_saves_and_survives_a_new_drive(trigger: str) -> None:
    flash = MemoryFlash()
    sim = make_sim(flash=flash)
    sim.drive.write_parameter(1, 80)
    sim.w(12, 4321)
    sim.w(18, 35)
    if trigger == "mode-50":
        sim.w(1, -50)
        sim.w(0, 0x20)
    elif trigger == "0x3802":
        sim.drive.write_parameter(0x3802, 0x11)
    elif trigger == "0x1010":
        sim.drive.od.write(0x1010, 1, 0x65766173)
    elif trigger == "0x2007":
        sim.drive.od.write(0x2007, 0, 0x11)
    else:
        sim.drive.apply("save", {})
    assert sim.drive.display == "--"
    assert not sim.drive.responding
    took = sim.run_until(lambda: sim.drive.responding, 10_000)
    assert took == pytest.approx(flashsave.SAVE_DURATION_US / 1000, abs=2)
    assert sim.drive.display == "Fr"
    assert flash.writes == 1
    fresh = make_sim(flash=flash)
    assert fresh.drive.read_parameter(1) == 80
    assert fresh.drive.read_register(12) == 4321
    assert fresh.drive.read_register(18) == 35
    assert fresh.drive.read_register(1) == (-50 if trigger == "mode-50" else 1)


def test_save_with_torque_on_completes_when_torque_goes_off() -> None:
    """Ch. 4: "verrà portata a termine solo quando verrà disabilitato il motore"."""
    sim = make_sim()
    sim.w(0, 0x03)
    sim.drive.write_parameter(0x3802, 0x11)
    assert sim.drive.responding and not sim.drive.saving
    sim.run(500)
    assert sim.flash.writes == 0
    sim.w(0, 0x00)
    assert sim.drive.saving
    sim.run_until(lambda: sim.drive.responding, 5_000)
    assert sim.flash.writes == 1


def test_canopen_save_sequence_ends_in_ready_to_switch_on() -> None:
    """Ch. 4: 0x0002, 0x1010:1 = 0x65766173, 0x0006, wait for statusword bit 0."""
    sim = make_sim()
    sim.cw(*CANOPEN_ENABLE)
    sim.cw(0x0002)
    sim.drive.od.write(0x1010, 1, 0x65766173)
    sim.cw(0x0006)
    assert sim.drive.statusword & 0x0001 == 0  # still saving
    took = sim.run_until(lambda: sim.drive.statusword & 0x0001, 5_000)
    assert took == pytest.approx(3000, abs=5)
    assert sim.drive.state is State.READY_TO_SWITCH_ON


@pytest.mark.parametrize("off", [0x0006, 0x0007])
def test_a_save_asked_in_torque_keeps_bit_0_low_until_it_is_done(off: int) -> None:
    """Ch. 4: a save asked with the motor enabled completes when it is disabled, and "il
    salvataggio è completo quando il bit 0 di StatusWord vale 1". 0x1010:1 written in
    Operation enabled, then 0x0006 (or 0x0007): bit 0 read 1 at once, 3 s before the save
    ended (review, session 11). The torque-off now leaves the drive where the manual's own
    sequence saves (Switch on disabled, 0x0002); the command completes after the save."""
    sim = make_sim()
    sim.cw(*CANOPEN_ENABLE)
    assert sim.drive.state is State.OPERATION_ENABLED
    sim.drive.od.write(0x1010, 1, 0x65766173)
    sim.run(100)
    assert sim.flash.writes == 0 and not sim.drive.saving  # in torque: pending
    sim.cw(off)
    assert not sim.drive.state.in_torque
    assert sim.drive.statusword & 0x0001 == 0
    if off == 0x0007:  # Switched on is no step from Switch on disabled: 0x0006 first
        sim.run_until(lambda: not sim.drive.saving, 5_000)
        assert sim.drive.state is State.SWITCH_ON_DISABLED and sim.flash.writes == 1
        assert sim.drive.statusword & 0x0001 == 0
        sim.cw(0x0006)
        assert sim.drive.state is State.READY_TO_SWITCH_ON
        return
    took = sim.run_until(lambda: sim.drive.statusword & 0x0001, 5_000)
    assert took >= flashsave.SAVE_DURATION_US / 1000 - 2
    assert sim.flash.writes == 1 and sim.drive.state is State.READY_TO_SWITCH_ON


def test_power_cut_during_a_save_keeps_the_old_content() -> None:
    flash = MemoryFlash()
    sim = make_sim(flash=flash)
    sim.w(12, 1111)
    sim.drive.apply("save", {})
    sim.run(3100)
    sim.w(12, 2222)
    sim.drive.apply("save", {})
    sim.run(1000)
    sim.drive.apply("power", {"on": False})
    sim.run(5000)
    sim.drive.apply("power", {"on": True})
    sim.run(100)
    assert sim.drive.read_register(12) == 1111
    assert flash.writes == 1


def test_failed_flash_write_raises_alarm_9() -> None:
    flash = MemoryFlash(fail=True)
    sim = make_sim(flash=flash)
    sim.drive.apply("save", {})
    sim.run(3100)
    assert sim.drive.read_register(46) == 9


def test_corrupt_flash_at_power_up_raises_alarm_9_and_uses_defaults() -> None:
    sim = make_sim(flash=MemoryFlash(b'{"format": "fieldrig-servo/1", "parameters": '
                                     b'{"d1": 500}, "registers": {}}'))
    assert sim.drive.read_register(46) == 9
    assert sim.drive.read_parameter(1) == 20


def test_bad_save_values_are_refused() -> None:
    from devices.od import SdoAbort
    from devices.servo.errors import AccessError
    sim = make_sim()
    with pytest.raises(AccessError):
        sim.drive.write_parameter(0x3802, 0x12)
    with pytest.raises(SdoAbort):
        sim.drive.od.write(0x1010, 1, 0x12345678)
    with pytest.raises(SdoAbort):
        sim.drive.od.write(0x2007, 0, 0x10)
    assert not sim.drive.saving


def test_node_number_and_fieldbus_are_read_at_power_up_only() -> None:
    """Ch. 2: "Il numero nodo è letto solamente all'accensione del drive"."""
    flash = MemoryFlash()
    sim = make_sim(DriveConfig(node_id=1), flash=flash)
    sim.drive.write_parameter(20, 7)  # c7
    sim.drive.write_parameter(22, 5)  # c9 = CANopen
    assert (sim.drive.node_id, sim.drive.fieldbus) == (1, "modbus")
    assert sim.drive.read_parameter(20) == 7
    sim.drive.apply("power", {"on": False})
    sim.drive.apply("power", {"on": True})
    assert (sim.drive.node_id, sim.drive.fieldbus) == (1, "modbus")  # not saved: lost
    sim.drive.write_parameter(20, 7)
    sim.drive.write_parameter(22, 5)
    sim.drive.apply("save", {})
    sim.run(3100)
    sim.drive.apply("power", {"on": False})
    sim.drive.apply("power", {"on": True})
    assert (sim.drive.node_id, sim.drive.fieldbus) == (7, "canopen")


def test_modbus_node_number_is_1_to_90() -> None:
    """Ch. 2 "Configurazione della rete": with c9 = 3 c7 "può assumere ogni valore tra 1 e 90";
    ch. 4: with c9 = 5 "qualsiasi valore compreso tra 1 e 99". c7 is checked against the c9
    stored now, so a technician moving a drive to CANopen writes c9 first, then c7."""
    sim = make_sim(DriveConfig(node_id=1), flash=MemoryFlash())
    sim.drive.write_parameter(20, 90)
    for node in (91, 95, 99):
        with pytest.raises(AccessError) as exc:
            sim.drive.write_parameter(20, node)
        assert exc.value.kind == "value"
    assert sim.drive.read_parameter(20) == 90
    sim.drive.write_parameter(22, 5)  # c9 = CANopen
    sim.drive.write_parameter(20, 99)
    assert sim.drive.read_parameter(20) == 99
    sim.drive.write_parameter(22, 3)  # back to Modbus: c7 = 99 stays, the line ignores it
    with pytest.raises(AccessError):
        sim.drive.write_parameter(20, 95)
    assert sim.drive.read_parameter(20) == 99


def test_rig_node_number_range_follows_the_fieldbus() -> None:
    """A Modbus drive at node 91..99 is a config error (ch. 2: 1..90); CANopen takes 1..99."""
    for fieldbus in ("canopen", "ethercat", "profinet"):
        assert make_sim(DriveConfig(node_id=99, fieldbus=fieldbus)).drive.node_id == 99
    assert make_sim(DriveConfig(node_id=1, parameters={"c9": 5, "c7": 95})).drive.node_id == 95
    # c9 = 5 in parameters: the drive powers up on CANopen, where node 95 is fine
    assert make_sim(DriveConfig(node_id=95, parameters={"c9": 5})).drive.node_id == 95
    with pytest.raises(ValueError, match=r"outside 1\.\.90 on Modbus"):
        DriveConfig(node_id=95, fieldbus="canopen", parameters={"c9": 3})
    assert make_sim(DriveConfig(node_id=90)).drive.node_id == 90


def test_powered_off_drive_does_not_respond() -> None:
    sim = make_sim()
    sim.drive.apply("power", {"on": False})
    assert not sim.drive.responding
    assert sim.drive.display == ""
    assert sim.drive.snapshot()["powered"] is False


def test_rig_values_for_first_power_up() -> None:
    """A rig can preset keypad parameters and registers; bad ones are refused up front."""
    sim = make_sim(DriveConfig(parameters={"D3": 80}, registers={12: 5000}, feed_constant=60))
    assert sim.drive.read_parameter(3) == 80
    assert sim.drive.read_register(12) == 5000
    assert sim.drive.read_register(2) == 60
    for bad in ({"parameters": {"zz": 1}}, {"parameters": {"d1": 0}},
                {"registers": {200: 1}}, {"registers": {5: 1}},
                {"registers": {27: 3}}, {"node_id": 0}, {"fieldbus": "profibus"},
                {"start_position": 1e9}, {"node_id": 91}, {"node_id": 99},
                {"parameters": {"c7": 95}}, {"parameters": {"C7": 91}},
                {"node_id": 95, "fieldbus": "canopen", "parameters": {"c9": 3}}):
        with pytest.raises(ValueError):
            DriveConfig(**bad)
