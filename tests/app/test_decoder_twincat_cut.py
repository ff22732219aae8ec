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


def test_an_alarm_number_in_hex_without_its_name() -> None:
    """The event log writes a FastCAT alarm 'alarm 0x10 NO_MOD module 0'; a trainee typing
    'alarm 0x10' got "give hex bytes". It reads the FastCAT codes 0x10 and drive alarm 16
    (0x10: the drive's display counts in decimal, seed 004 ch. 5)."""
    titles = [m.title for m in decode("alarm 0x10")]
    assert "FastCAT coupler:0x10" in titles and "FastCAT module:0x10" in titles, titles
    assert "Drive alarm 16 FOLLOWING_ERROR" in titles, titles
    assert [m.title for m in decode("alarm 0x3702")] == [
        "CPX-E Text-ID 0x3702: CPX error number 2"]
