"""The built-in master's SDO download (devices/esm.py ``CoeMailbox.sdo_download``, its start-up
commands' path) answers as the wire's (``Face.download_raw``): the object, then its access, then
the length of the data, each abort naming the object written (DS301; ETG.1000.6 CoE).

The FastCAT, the TRS-CAT and the CPX-E-EC take the shared path; the drive has its own (seed 004
ch. 4's length rule, devices/coe/mailbox.py)."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from test_faces import line_rig

from app.ethercat_wire.faces import face_for
from devices.od import AbortCode, DataType, OdEntry, SdoAbort

SHARED = ("fastcat", "trscat", "cpx")
NUMERIC = (DataType.INTEGER16, DataType.INTEGER32, DataType.UNSIGNED16, DataType.UNSIGNED32)


@pytest.fixture(scope="module")
def rig():
    return line_rig("PREOP")


def abort_of(call: Callable[[], object]) -> tuple[AbortCode, int, int]:
    with pytest.raises(SdoAbort) as info:
        call()
    return info.value.code, info.value.index, info.value.sub


def a_writable_word(model) -> OdEntry:
    """The first writable object of two or four bytes the master can reach."""
    return next(e for e in model.od if e.access.writable and e.dtype in NUMERIC
                and e.reachable is None)


@pytest.mark.parametrize("device", SHARED)
@pytest.mark.parametrize("data", (b"\x01\x00", b"\x01\x00\x00\x00", b"\x01\x00\x00\x00\x00"),
                         ids=("2 bytes", "4 bytes", "5 bytes"))
def test_a_read_only_object_answers_read_only_whatever_the_length(rig, device: str,
                                                                  data: bytes) -> None:
    """0x1018:1 (UDINT, ro) written with 2, 4 or 5 bytes: 0x06010002 "Attempt to write a read
    only object" for 0x1018:1, not a length abort for 0x0000:0."""
    model = rig.devices[device]
    before = model.od.peek(0x1018, 1)
    assert abort_of(lambda: model.sdo_download(0x1018, 1, data)) == \
        (AbortCode.READ_ONLY, 0x1018, 1)
    assert abort_of(lambda: face_for(model).download_raw(model, 0x1018, 1, data)) == \
        (AbortCode.READ_ONLY, 0x1018, 1)
    assert model.od.peek(0x1018, 1) == before


@pytest.mark.parametrize("device", SHARED)
@pytest.mark.parametrize("extra", (-1, 1), ids=("short", "long"))
def test_a_wrong_length_names_the_object_written(rig, device: str, extra: int) -> None:
    """A writable object sent one byte short or long: 0x06070013 / 0x06070012 for that
    object's index and sub, as on the wire; the value stays."""
    model = rig.devices[device]
    entry = a_writable_word(model)
    data = bytes(entry.bit_length // 8 + extra)
    code = AbortCode.LENGTH_TOO_HIGH if extra > 0 else AbortCode.LENGTH_TOO_LOW
    before = model.od.peek(entry.index, entry.sub)
    assert abort_of(lambda: model.sdo_download(entry.index, entry.sub, data)) == \
        (code, entry.index, entry.sub)
    assert abort_of(lambda: face_for(model).download_raw(model, entry.index, entry.sub,
                                                         data)) == (code, entry.index, entry.sub)
    assert model.od.peek(entry.index, entry.sub) == before


@pytest.mark.parametrize("device", SHARED)
def test_an_absent_object_answers_first(rig, device: str) -> None:
    """No object: 0x06020000 before any length check (a wrong length to a missing object)."""
    model = rig.devices[device]
    assert abort_of(lambda: model.sdo_download(0x5FFF, 0, b"\x01")) == \
        (AbortCode.NO_OBJECT, 0x5FFF, 0)
