"""The shared object dictionary: access rights, ranges and DS301 abort codes."""

import pytest

from devices.od import (
    AbortCode,
    Access,
    DataType,
    ObjectDictionary,
    OdEntry,
    SdoAbort,
    decode,
    encode,
)


@pytest.fixture
def od() -> ObjectDictionary:
    od = ObjectDictionary()
    od.add(OdEntry(0x1000, 0, "Device type", DataType.UNSIGNED32, Access.RO, 0x1389))
    od.add(OdEntry(0x2000, 1, "Filter", DataType.UNSIGNED16, Access.RW, 4000, low=1, high=10000))
    od.add(OdEntry(0x2001, 0, "Command", DataType.UNSIGNED8, Access.WO, 0))
    od.add(OdEntry(0x10F3, 6, "Message", DataType.OCTET_STRING, Access.RO, b"\x00\x01"))
    return od


@pytest.mark.parametrize(("op", "index", "sub", "value", "code"), [
    ("write", 0x1000, 0, 1, AbortCode.READ_ONLY),
    ("read", 0x2001, 0, None, AbortCode.WRITE_ONLY),
    ("read", 0x3000, 0, None, AbortCode.NO_OBJECT),
    ("read", 0x2000, 9, None, AbortCode.NO_SUBINDEX),
    ("write", 0x2000, 1, 0, AbortCode.VALUE_TOO_LOW),
    ("write", 0x2000, 1, 10001, AbortCode.VALUE_TOO_HIGH),
    ("write", 0x2000, 1, "x", AbortCode.TYPE_MISMATCH),
])
def test_aborts(od: ObjectDictionary, op: str, index: int, sub: int, value, code) -> None:
    with pytest.raises(SdoAbort) as info:
        od.write(index, sub, value) if op == "write" else od.read(index, sub)
    assert info.value.code is code


def test_write_then_read_and_setter(od: ObjectDictionary) -> None:
    seen = []
    od.entry(0x2000, 1).setter = seen.append
    od.write(0x2000, 1, 10000)
    assert od.read(0x2000, 1) == 10000 and seen == [10000]


@pytest.mark.parametrize(("dtype", "value", "raw"), [
    (DataType.INTEGER16, -2, b"\xfe\xff"),
    (DataType.UNSIGNED32, 0x12000000, b"\x00\x00\x00\x12"),
    (DataType.VISIBLE_STRING, "FastCAT", b"FastCAT"),
    (DataType.OCTET_STRING, b"\x01\x02", b"\x01\x02"),
])
def test_codec_round_trip(dtype: DataType, value, raw: bytes) -> None:
    assert encode(dtype, value) == raw and decode(dtype, raw) == value


def test_octet_string_entry(od: ObjectDictionary) -> None:
    assert od.read(0x10F3, 6) == b"\x00\x01"
    assert od.entry(0x10F3, 6).bit_length == 16
