"""Seed 001 §9.3.7 gives 0x7100 "power error" to two causes: TRS bus overcurrent and
undervoltage. The TRS-CAT's emergency tells them apart by its error register (0x1001: bit 1
current, bit 2 voltage; devices/trscat/diagnostics.py FAULTS); the tab listed both for either."""

from __future__ import annotations

import pytest

from app.decoder import TRSCAT, decode
from devices.trscat.diagnostics import FAULTS, emergency_frame


@pytest.mark.parametrize("name", ["TRS_OVERCURRENT", "TRS_UNDERVOLTAGE"])
def test_the_register_picks_the_power_error(name: str) -> None:
    fault = FAULTS[name]
    frame = emergency_frame(fault, 0)
    logged = f"CoE - Emergency (Hex: {fault.code:04x}, {frame[2]:02x}, " \
             f"{frame[3:].hex(' ')}')."
    for query in (logged, frame.hex(" ")):
        found = [m for m in decode(query) if m.family == TRSCAT]
        assert [m.text.split(";")[0] for m in found] == [fault.text], (query, found)


def test_the_bare_code_still_reads_both() -> None:
    found = [m for m in decode("0x7100") if m.family == TRSCAT]
    assert len(found) == 2, found


def test_a_register_neither_cause_sets_reads_both() -> None:
    """A register the TRS-CAT does not send with 0x7100: no guess, both causes."""
    found = [m for m in decode("7100 01 00 00 00 00 00") if m.family == TRSCAT]
    assert len(found) == 2, found
