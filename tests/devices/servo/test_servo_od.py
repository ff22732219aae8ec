"""The CiA 402 / manufacturer object dictionary (seed 004 ch. 4 "Oggetti implementati", ch. 5
0x603F and 0x2007) as a view on the same state as the registers."""

from __future__ import annotations

import pytest
from servo_helpers import make_sim

from devices.od import AbortCode, Access, DataType, SdoAbort

# object -> register it shows (ch. 4 names vs the ch. 1 quick reference)
REGISTER_OBJECTS = [
    (0x6064, 0, 6), (0x6065, 0, 3), (0x6066, 0, 4), (0x606C, 0, 8), (0x606D, 0, 14),
    (0x606E, 0, 15), (0x606F, 0, 16), (0x6070, 0, 17), (0x607A, 0, 9), (0x607C, 0, 19),
    (0x6081, 0, 12), (0x6083, 0, 10), (0x6084, 0, 11), (0x6086, 0, 27), (0x6092, 1, 2),
    (0x6098, 0, 18), (0x6099, 1, 20), (0x6099, 2, 21), (0x609A, 0, 22), (0x60C2, 1, 47),
    (0x60FD, 0, 48), (0x60FE, 1, 50), (0x60FE, 2, 49), (0x60FF, 0, 13), (0x2001, 0, 7),
    (0x3000, 0, 24), (0x3001, 0, 25), (0x3002, 0, 26), (0x3100, 0, 28), (0x3101, 0, 29),
    (0x3201, 0, 30), (0x3202, 0, 31), (0x3301, 0, 32), (0x3302, 0, 33), (0x3401, 0, 34),
    (0x3402, 0, 35), (0x3501, 0, 36), (0x3502, 0, 37), (0x3601, 0, 38), (0x3604, 0, 41),
    (0x3701, 0, 42), (0x3704, 0, 45)]
SAMPLE = {DataType.INTEGER32: -12345, DataType.UNSIGNED32: 4321, DataType.UNSIGNED16: 77,
          DataType.INTEGER16: -77, DataType.UNSIGNED8: 12, DataType.INTEGER8: -1}


@pytest.mark.parametrize(("index", "sub", "n"), REGISTER_OBJECTS)
def test_object_and_register_are_one_value(index: int, sub: int, n: int) -> None:
    sim = make_sim()
    entry = sim.drive.od.entry(index, sub)
    assert sim.drive.od.read(index, sub) == sim.drive.read_register(n)
    if not entry.access.writable:
        with pytest.raises(SdoAbort) as err:
            sim.drive.od.write(index, sub, 0)
        assert err.value.code is AbortCode.READ_ONLY
        return
    value = {27: -1, 47: 5}.get(n, SAMPLE[entry.dtype])  # R27 takes 0, -1, -2 only
    sim.drive.od.write(index, sub, value)
    assert sim.drive.od.read(index, sub) == value
    assert sim.drive.read_register(n) == value


def test_a_register_write_shows_in_the_object() -> None:
    sim = make_sim()
    sim.drive.write_register(19, -1000)
    assert sim.drive.od.read(0x607C, 0) == -1000
    sim.drive.write_register(20, -5)  # S32 register behind a UNSIGNED32 object
    assert sim.drive.od.read(0x6099, 1) == 0xFFFF_FFFB


@pytest.mark.parametrize(("index", "sub", "value"), [
    (0x6066, 0, 0x2000), (0x6060, 0, 2), (0x6086, 0, 1), (0x3001, 0, 0x21), (0x3002, 0, 0),
    (0x6098, 0, 0x100), (0x6092, 1, 0x40000)])
def test_out_of_range_writes_abort_and_change_nothing(index: int, sub: int, value: int) -> None:
    sim = make_sim()
    before = sim.drive.snapshot()
    with pytest.raises(SdoAbort) as err:
        sim.drive.od.write(index, sub, value)
    assert err.value.code in (AbortCode.VALUE_RANGE, AbortCode.VALUE_TOO_HIGH,
                              AbortCode.VALUE_TOO_LOW)
    assert sim.drive.snapshot() == before


def test_access_as_printed() -> None:
    """0x6060 wo, 0x6061 ro, 0x6041 ro, 0x60C1:1 wo (ch. 4 table)."""
    sim = make_sim()
    od = sim.drive.od
    assert od.entry(0x6060, 0).access is Access.WO
    with pytest.raises(SdoAbort) as err:
        od.read(0x6060, 0)
    assert err.value.code is AbortCode.WRITE_ONLY
    od.write(0x6060, 0, 3)
    assert od.read(0x6061, 0) == 3 == sim.drive.read_register(1)
    with pytest.raises(SdoAbort):
        od.write(0x6041, 0, 0)
    with pytest.raises(SdoAbort):
        od.read(0x60C1, 1)
    assert od.read(0x6092, 2) == 1  # "sub-index 2 (Shaft Revolutions) è fissato ad 1"
    assert od.read(0x6502, 0) & 0x65 == 0x65


def test_0x2000_parameter_write_handshake() -> None:
    """Ch. 4: value to 2000.2, address to 2000.1; the address returns to 0 when done, the
    change is active after about 20 ms."""
    sim = make_sim()
    od = sim.drive.od
    od.write(0x2000, 2, 40)
    od.write(0x2000, 1, 2)
    assert od.read(0x2000, 1) == 2
    assert sim.drive.read_parameter(2) == 50
    took = sim.run_until(lambda: od.read(0x2000, 1) == 0, 100)
    assert took == pytest.approx(20, abs=1)
    assert sim.drive.read_parameter(2) == 40


def test_0x2000_parameter_read_handshake() -> None:
    """Write the address to 2000.3, poll until 0 (>= 3 ms), read 2000.4."""
    sim = make_sim()
    od = sim.drive.od
    od.write(0x2000, 3, 1)
    took = sim.run_until(lambda: od.read(0x2000, 3) == 0, 100)
    assert took == pytest.approx(3, abs=1)
    assert od.read(0x2000, 4) == 20


def test_0x2000_refuses_a_bad_address_or_value() -> None:
    sim = make_sim()
    od = sim.drive.od
    od.write(0x2000, 2, 100)
    with pytest.raises(SdoAbort):
        od.write(0x2000, 1, 1)  # d1 takes 1..99
    with pytest.raises(SdoAbort):
        od.write(0x2000, 1, 23)  # no parameter at 23
    assert od.read(0x2000, 1) == 0
    sim.run(30)
    assert sim.drive.read_parameter(1) == 20


def test_0x2005_and_0x2006_reach_registers_and_parameters() -> None:
    """Address < 99: a parameter; 0x8000..0x8FFF: a register (ch. 4)."""
    sim = make_sim()
    od = sim.drive.od
    od.write(0x2006, 2, 12345)
    od.write(0x2006, 1, 0x800C)
    sim.run_until(lambda: od.read(0x2006, 1) == 0, 100)
    assert sim.drive.read_register(12) == 12345
    od.write(0x2005, 1, 0x800C)
    sim.run_until(lambda: od.read(0x2005, 1) == 0, 100)
    assert od.read(0x2005, 2) == 12345
    od.write(0x2005, 1, 3)
    sim.run(5)
    assert od.read(0x2005, 2) == 50
    with pytest.raises(SdoAbort):
        od.write(0x2005, 1, 0x8086)  # R134 does not exist


def test_16_bit_views() -> None:
    """0x2003 = low 16 bits of 0x6064; 0x2002 sets the interpolation set-point's low bits."""
    sim = make_sim()
    d = sim.drive
    d.od.write(0x60C1, 1, 65530)
    d.od.write(0x2002, 0, 4)  # 65540 has the low bits 0x0004: the set-point wraps forward
    assert d.ip_set_point == 65540
    d.od.write(0x2002, 0, -6)  # 0xFFFA
    assert d.ip_set_point == 65530
    assert d.od.read(0x2003, 0) == 0


def test_writes_to_a_powered_off_drive_abort() -> None:
    sim = make_sim()
    sim.drive.apply("power", {"on": False})
    with pytest.raises(SdoAbort) as err:
        sim.drive.od.write(0x6040, 0, 0x06)
    assert err.value.code is AbortCode.CANNOT_STORE_STATE
