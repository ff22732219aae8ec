"""The PDO assignment rules both EtherCAT CoE slaves with a writable 0x1C12 / 0x1C13 share
(devices/pdo_assign.py; ETG.1000.6 / CiA 301: sub 0 = 0, the entries, sub 0 = n): the drive's
(seed 004 ch. 5) and the CPX-E-EC's 0x1C13 (seed 002 l. 539-541). Each device gives only the
PDOs it has, the state guard and the number of entries."""

from __future__ import annotations

import pytest

from devices.od import AbortCode, SdoAbort
from devices.pdo_assign import PdoAssignment


def _abort(call, *args) -> int:
    with pytest.raises(SdoAbort) as exc:
        call(*args)
    return exc.value.code


def test_the_sequence_and_its_aborts() -> None:
    writable = [True]
    a = PdoAssignment(0x1C13, allowed=(0x1A00, 0x1A01, 0x1A40), size=3,
                      may_write=lambda: writable[0])
    a.assign([0x1A01, 0x1A00])
    assert (a.count, a.assigned) == (2, (0x1A01, 0x1A00))
    assert _abort(a.set_entry, 1, 0x1A40) == AbortCode.UNSUPPORTED_ACCESS  # sub 0 is not 0
    a.set_count(0)
    assert _abort(a.set_entry, 1, 0x1A02) == AbortCode.VALUE_RANGE  # not a PDO it has
    a.set_entry(1, 0x1A40)
    assert _abort(a.set_count, 4) == AbortCode.VALUE_TOO_HIGH  # past the entries
    a.set_entry(2, 0x1A40)
    assert _abort(a.set_count, 2) == AbortCode.VALUE_RANGE  # twice
    a.set_entry(3, 0)
    assert _abort(a.set_count, 3) == AbortCode.VALUE_RANGE  # an empty entry inside
    writable[0] = False
    assert _abort(a.set_count, 1) == AbortCode.CANNOT_STORE_STATE
    assert _abort(a.set_entry, 1, 0x1A00) == AbortCode.CANNOT_STORE_STATE
    assert a.count == 0  # nothing taken while refused


def test_the_abort_names_the_object_written() -> None:
    a = PdoAssignment(0x1C12, allowed=range(0x1600, 0x1604), size=4)
    with pytest.raises(SdoAbort) as exc:
        a.set_count(5)
    assert (exc.value.index, exc.value.sub) == (0x1C12, 0)
