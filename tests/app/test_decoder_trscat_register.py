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
    frame = emergency_frame(fault, 0, fault.register)
    logged = f"CoE - Emergency (Hex: {fault.code:04x}, {frame[2]:02x}, " \
             f"{frame[3:].hex(' ')}')."
    for query in (logged, frame.hex(" ")):
        found = [m for m in decode(query) if m.family == TRSCAT]
        assert [m.text.split(";")[0] for m in found] == [fault.text], (query, found)


def test_the_bare_code_still_reads_both() -> None:
    found = [m for m in decode("0x7100") if m.family == TRSCAT]
    assert len(found) == 2, found


@pytest.mark.parametrize(("register", "name"), [(0x13, "TRS_OVERCURRENT"),
                                              (0x15, "TRS_UNDERVOLTAGE")])
def test_another_active_error_s_bits_do_not_hide_the_cause(register: int, name: str) -> None:
    """The register is 0x1001 when the EMCY is sent (DS301): with a 0x7500 (0x11) active too
    it holds that error's bits besides the cause's own."""
    found = [m for m in decode(f"7100 {register:02x} 00 00 00 00 00") if m.family == TRSCAT]
    assert [m.text.split(";")[0] for m in found] == [FAULTS[name].text], found


def test_both_bits_set_reads_both() -> None:
    """Current and voltage bits both set (an undervoltage and a 0x3220 active, say): no
    guess, both causes."""
    found = [m for m in decode("7100 07 00 00 00 00 00") if m.family == TRSCAT]
    assert len(found) == 2, found


def test_a_register_neither_cause_sets_reads_both() -> None:
    """A register the TRS-CAT does not send with 0x7100: no guess, both causes."""
    found = [m for m in decode("7100 01 00 00 00 00 00") if m.family == TRSCAT]
    assert len(found) == 2, found
