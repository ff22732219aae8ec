"""Which Modbus address map the drive serves is the drive's: parameter e3 = 9 moves it for
Siemens PLCs (seed 004 ch. 2 "Estensione della mappatura degli indirizzi per PLC Siemens"),
and the snapshot says so, for a view that words the addresses (docs/modbus.md "Addresses")."""

from __future__ import annotations

from servo_helpers import make_sim

from devices.servo.modbus_map import NORMAL, SIEMENS, parameter_address, register_address
from devices.servo.parameters import PARAMETER_BY_NAME

E3 = PARAMETER_BY_NAME["e3"].address


def test_the_snapshot_names_the_map_e3_selects() -> None:
    sim = make_sim()
    assert sim.drive.snapshot()["modbus_map"] == NORMAL
    sim.drive.write_parameter(E3, 9)
    sim.run(1)
    assert sim.drive.snapshot()["modbus_map"] == SIEMENS
    sim.drive.write_parameter(E3, 6)  # no parity: the normal map
    sim.run(1)
    assert sim.drive.snapshot()["modbus_map"] == NORMAL


def test_addresses_as_the_seed_s_examples() -> None:
    """Ch. 2 examples: d1 = 40002 = 0x9C42, d3 = 0x9C44, R00 = 0xAC41, R09 = 0xAC4A; the
    normal map d1 = 0x0001, R00 = 0x8000 (ch. 1)."""
    d1, d3 = PARAMETER_BY_NAME["d1"].address, PARAMETER_BY_NAME["d3"].address
    assert (parameter_address(d1, SIEMENS), parameter_address(d3, SIEMENS)) == (0x9C42, 0x9C44)
    assert (register_address(0, SIEMENS), register_address(9, SIEMENS)) == (0xAC41, 0xAC4A)
    assert (parameter_address(d1, NORMAL), register_address(0, NORMAL)) == (0x0001, 0x8000)
