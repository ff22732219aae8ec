"""0x10F3:5 "Flags" in each device's seed's words, as a trainee reads it in the Objects tab.

Seed 001 §9.3.7 (TRS-CAT): "default 0x00 tutti abilitati. Bit1 = 1: disabilita messaggi
informativi, Bit2 = 1: ... di attenzione, Bit3 = 1: ... di errore". Seed 002 (CPX-E-EC) Tab. 19:
bit 0 activates the Emergency Message; Tab. 18: bit 4, 0 Overwrite mode, 1 Acknowledge mode.
Before, "0x10F3:5 = 0x0011" read "no code and no alarm name".
"""

from __future__ import annotations

import pytest

from app.decoder import CPX, TRSCAT, DecodeError, Meaning, decode
from devices.cpx import history
from devices.trscat import diagnostics


def _one(found: list[Meaning], family: str) -> Meaning:
    mine = [m for m in found if m.family == family]
    assert len(mine) == 1, found
    return mine[0]


@pytest.mark.parametrize("query", [
    "0x10F3:5 = 0x0011", "0x10F3:5 17", "10F3:05 = 17",
    "0x10F3:5\tFlags\tU16\trw\t17 (0x0011)",  # the CPX-E-EC's Objects tab row
    "0x10F3:5\tFlags\tUINT\trw\t17 (0x0011)",
])
def test_the_cpx_flags_read_tab_18_and_19(query: str) -> None:
    m = _one(decode(query), CPX)
    assert m.title == "0x10F3:5 Flags = 0x0011"
    assert "bit 0 = 1: Emergency Message activated (Tab. 19)" in m.text, m.text
    assert "bit 4 = 1: Acknowledge mode (Tab. 18)" in m.text, m.text
    assert "seed 002 Tab. 18, 19" in m.source


def test_the_cpx_default_reads_overwrite_and_no_emergency() -> None:
    """Tab. 14: default 0x0000."""
    m = _one(decode("0x10F3:5 = 0"), CPX)
    assert "bit 0 = 0: Emergency Message deactivated (Tab. 19)" in m.text, m.text
    assert "bit 4 = 0: Overwrite mode (Tab. 18)" in m.text, m.text


def test_the_trscat_flags_read_seed_001s_bits() -> None:
    m = _one(decode("0x10F3:5 = 0x000A"), TRSCAT)
    assert "bit 1 = 1: info messages disabled" in m.text, m.text
    assert "bit 2 = 0: warning messages enabled" in m.text, m.text
    assert "bit 3 = 1: error messages disabled" in m.text, m.text
    assert m.source.startswith("seed 001 §9.3.7")


def test_a_bit_the_trscat_never_holds() -> None:
    """The TRS-CAT runs acknowledge mode for good: its writes keep bits 0-3 only."""
    m = _one(decode("0x10F3:5 = 0x0010"), TRSCAT)
    assert "bit 4 = 1: not a bit of the TRS-CAT's 0x10F3:5" in m.text, m.text


def test_the_trscat_reads_etg1020s_bit5() -> None:
    """Set by the TRS-CAT when a new message is discarded (ETG.1020; §9.3.7 prints bits 1-3)."""
    m = _one(decode("0x10F3:5 = 0x0020"), TRSCAT)
    assert "bit 5 = 1: a new message discarded" in m.text, m.text


def test_the_words_are_the_models() -> None:
    assert history.FLAG_TEXT[history.FLAG_ACKNOWLEDGE][0].startswith("Acknowledge mode")
    assert diagnostics.FLAG_TEXT[0x02][0] == "info messages disabled"


def test_the_address_alone_lists_the_bits() -> None:
    m = _one(decode("0x10F3:5"), CPX)
    assert "bit 4: 1 = Acknowledge mode" in m.text and "0 = Overwrite mode" in m.text, m.text


@pytest.mark.parametrize(("query", "hint"), [
    ("0x10F3:5 = 0x10000", "two bytes"),
    ("0x10F3:3 = 6", "0x10F3:5"),
    ("0x10F3:5 = banana", "give its value"),
])
def test_a_bad_flags_query_is_one_message(query: str, hint: str) -> None:
    with pytest.raises(DecodeError, match=hint):
        decode(query)
