"""The TwinCAT emergency line (seed 000 §7.1) as a trainee copies it from the event log."""

from __future__ import annotations

import pytest

from app.decoder import CPX, decode


@pytest.mark.parametrize("query", [
    "Hex: 2330, 83, ee 04 03 00 01",  # the bytes copied without the closing bracket
    "(Hex: 2330, 83, ee 04 03 00 01",
    "CoE - Emergency (Hex: 2330, 83, ee 04 03 00 01'.",
])
def test_a_twincat_emergency_copied_without_its_bracket(query: str) -> None:
    """The event log's TwinCAT line (seed 000 §7.1): a trainee who selects up to the last
    byte leaves the ')' behind; the tab said "no code and no alarm name"."""
    (m,) = [m for m in decode(query) if m.family == CPX]
    assert m.title == "CPX-E emergency code 0x2330"
    assert "Module 4, Wire break" in m.text and "byte 7 = 1" in m.text
    assert "Error register 0x83" in m.text
