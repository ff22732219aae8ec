"""Register map R00..R133 and parameters (seed 004 ch. 1 quick reference): addresses, ranges,
read-only registers, and refused writes that leave the drive unchanged."""

from __future__ import annotations

import pytest
from servo_helpers import make_sim

from devices.servo.errors import AccessError
from devices.servo.parameters import PARAMETER_BY_NAME, PARAMETERS, parameter_by_name_or_address
from devices.servo.registers import REGISTERS

S32 = (-0x8000_0000, 0x7FFF_FFFF)
# (register, low, high, "Si") as the quick reference prints them
QUICK_REFERENCE = [
    (0, 0, 0xFFFF, True), (1, -0x7F, 0x7F, True), (2, 0, 0x3FFFF, True),
    (3, 0, 0xFFFF_FFFF, True), (4, 0, 0x1FFF, True), (5, 0, 0xFF, False),
    (6, *S32, False), (7, *S32, False), (8, *S32, False), (9, *S32, False),
    (10, 0, 0x7FFF_FFFF, True), (11, 0, 0x7FFF_FFFF, True), (12, 0, 0x7FFF_FFFF, True),
    (13, *S32, False), (14, 0, 0xFFFF, True), (15, 0, 0x7FFF, True), (16, 0, 0xFFFF, True),
    (17, 0, 0x7FFF, True), (18, 0, 0xFF, True), (19, *S32, True), (20, *S32, True),
    (21, 0, 0x7FFF_FFFF, True), (22, 0, 0x7FFF_FFFF, True), (23, -0x8000, 0x7FFF, False),
    (24, 1, 0x7FFF, True), (25, 1, 0x20, True), (26, 1, 0xFF, True),
    (27, -0x8000, 0x7FFF, True), (28, 1, 0x63, True), (29, 1, 0x63, True),
    (30, *S32, True), (35, -0x8000, 0x7FFF, True), (42, *S32, True),
    (43, -0x8000, 0x7FFF, True), (46, 0, 0xFF, False), (47, 0, 0xFF, True),
    (48, 0, 0xFFFF_FFFF, False), (49, 0, 0xFFFF_FFFF, True), (50, 0, 0xFFFF_FFFF, True),
    (61, *S32, True), (65, *S32, True), (72, *S32, True), (73, *S32, True), (133, *S32, True)]
READ_ONLY = {5, 6, 8, 23, 32, 33, 36, 37, 46, 48, 73}


def test_every_register_r00_to_r133_at_0x8000_plus_n() -> None:
    assert sorted(REGISTERS) == list(range(134))
    assert all(spec.address == 0x8000 + n for n, spec in REGISTERS.items())


@pytest.mark.parametrize(("n", "low", "high", "saveable"), QUICK_REFERENCE)
def test_ranges_as_printed(n: int, low: int, high: int, saveable: bool) -> None:
    spec = REGISTERS[n]
    assert (spec.low, spec.high, spec.saveable) == (low, high, saveable)


@pytest.mark.parametrize("n", sorted(READ_ONLY))
def test_read_only_registers(n: int) -> None:
    sim = make_sim()
    before = sim.drive.read_register(n)
    with pytest.raises(AccessError) as err:
        sim.drive.write_register(n, 0)
    assert err.value.kind == "readonly"
    assert sim.drive.read_register(n) == before


WRITABLE = sorted(n for n, s in REGISTERS.items() if s.writable and n not in (0, 1))


def _bad_values(low: int, high: int, signed: bool) -> list[int]:
    """Just outside the range, or outside 32 bits where the range fills them."""
    above = 1 << 32 if high == 0xFFFF_FFFF or (signed and high == 0x7FFF_FFFF) else high + 1
    below = -(1 << 31) - 1 if high == 0xFFFF_FFFF or low == -(1 << 31) else low - 1
    return [above, below]


@pytest.mark.parametrize("n", WRITABLE)
def test_out_of_range_values_are_refused_and_change_nothing(n: int) -> None:
    spec = REGISTERS[n]
    low, high = (min(spec.allowed), max(spec.allowed)) if spec.allowed else (spec.low, spec.high)
    sim = make_sim()
    sim.drive.write_register(n, high)
    assert sim.drive.read_register(n) == high
    sim.drive.write_register(n, low)
    assert sim.drive.read_register(n) == low
    for bad in _bad_values(spec.low, spec.high, spec.signed):
        with pytest.raises(AccessError) as err:
            sim.drive.write_register(n, bad)
        assert err.value.kind == "value"
    assert sim.drive.read_register(n) == low


def test_32_bit_wire_values_are_read_as_the_register_holds_them() -> None:
    """FF FF FF CE in R01 is -50 (ch. 2 save example); -1 in R03 is 0xFFFFFFFF."""
    sim = make_sim()
    sim.drive.write_register(1, 0xFFFF_FFCE)
    assert sim.drive.read_register(1) == -50
    sim.drive.write_register(3, -1)
    assert sim.drive.read_register(3) == 0xFFFF_FFFF
    sim.drive.write_register(19, 0xFFFF_FC18)
    assert sim.drive.read_register(19) == -1000


@pytest.mark.parametrize("value", [0, 2, 4, 5, 8, -3, -128, 127])
def test_only_the_implemented_modes(value: int) -> None:
    sim = make_sim()
    with pytest.raises(AccessError):
        sim.drive.write_register(1, value)
    assert sim.drive.read_register(1) == 1


@pytest.mark.parametrize("value", [1, 2, -3, 5])
def test_only_the_three_motion_profiles(value: int) -> None:
    sim = make_sim()
    with pytest.raises(AccessError):
        sim.drive.write_register(27, value)


@pytest.mark.parametrize("n", [-1, 134, 0x8000, 1000])
def test_no_such_register(n: int) -> None:
    sim = make_sim()
    assert not sim.drive.is_register(n)
    with pytest.raises(AccessError) as err:
        sim.drive.read_register(n)
    assert err.value.kind == "address"


# (name, address) of the quick reference, "d1 ... 01 (0x0001)" etc.
PARAMETER_ADDRESSES = {
    "d1": 1, "d2": 2, "d3": 3, "d4": 4, "d5": 5, "d6": 6, "d7": 7, "d8": 8, "e1": 9, "e2": 10,
    "e3": 58, "e4": 55, "f1": 11, "f2": 12, "f3": 13, "c1": 14, "c2": 15, "c3": 16, "c4": 17,
    "c5": 18, "c6": 19, "c7": 20, "c8": 21, "c9": 22, "i1": 35, "i2": 36, "i3": 37, "i4": 38,
    "i5": 39, "i6": 90, "i7": 99, "o1": 81, "o2": 82, "o3": 83, "p1": 41, "p2": 42, "p3": 43,
    "p4": 44, "p5": 45, "p6": 46, "p7": 47, "a1": 48, "a2": 49, "a3": 50, "a4": 51, "a5": 52,
    "a6": 53, "h1": 59, "h2": 60, "h3": 61, "h4": 62, "h5": 63, "h6": 64, "h7": 65, "h8": 66,
    "h9": 67, "n1": 40}


def test_parameter_addresses() -> None:
    assert {name: spec.address for name, spec in PARAMETER_BY_NAME.items()} \
        == PARAMETER_ADDRESSES
    sim = make_sim()
    assert sim.drive.parameter_addresses() == sorted(PARAMETER_ADDRESSES.values())


@pytest.mark.parametrize("name", sorted(n for n, s in PARAMETER_BY_NAME.items()
                                        if s.unit == "%"))
def test_percent_parameters_take_1_to_99(name: str) -> None:
    sim = make_sim()
    address = PARAMETER_ADDRESSES[name]
    for bad in (0, 100):
        with pytest.raises(AccessError):
            sim.drive.write_parameter(address, bad)
    sim.drive.write_parameter(address, 99)
    assert sim.drive.read_parameter(address) == 99


@pytest.mark.parametrize("name", ["o1", "o2", "o3"])
def test_monitor_parameters_are_read_only(name: str) -> None:
    sim = make_sim()
    with pytest.raises(AccessError) as err:
        sim.drive.write_parameter(PARAMETER_ADDRESSES[name], 1)
    assert err.value.kind == "readonly"


@pytest.mark.parametrize("address", [0, 23, 34, 54, 100, 0x7FFF, 0x3803])
def test_no_such_parameter(address: int) -> None:
    sim = make_sim()
    with pytest.raises(AccessError) as err:
        sim.drive.read_parameter(address)
    assert err.value.kind == "address"
    assert address not in PARAMETERS


@pytest.mark.parametrize(("key", "name"), [("d3", "d3"), ("D3", "d3"), ("3", "d3"),
                                           ("0x0016", "c9"), (20, "c7"), ("H2", "h2")])
def test_parameters_by_name_or_address(key: str | int, name: str) -> None:
    assert parameter_by_name_or_address(key).name == name


def test_motor_current_readings_follow_the_motion() -> None:
    """o1 (instantaneous current) rises while accelerating and with a blocked load."""
    sim = make_sim()
    assert sim.drive.read_parameter(81) == 0
    sim.w(1, 3)
    sim.w(13, 30000)
    sim.w(0, 0x03)
    sim.run(50)
    accelerating = sim.drive.read_parameter(81)
    sim.run(500)
    cruising = sim.drive.read_parameter(81)
    assert accelerating > cruising > 0
    sim.drive.apply("jam_load", {"active": True})
    sim.run(20)
    assert sim.drive.read_parameter(81) > accelerating
