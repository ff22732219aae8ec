"""The Codes tab reads a 32-bit 0x1003 entry of the drive: the 0x603F code in bits 0-15, the
alarm number in bits 16-31 (docs/canopen.md, seed 004 ch. 4 "Emergency Message")."""

from __future__ import annotations

from app.decoder import decode
from app.decoder_meaning import DecodeError


def test_codes_tab_reads_the_0x1003_word() -> None:
    found = [m for m in decode("0x00108611") if "0x1003" in m.title]
    assert [m.text for m in found] == ["0x00108611 = alarm 16 FOLLOWING_ERROR, code 0x8611."]


def test_a_word_whose_code_is_not_the_alarms_is_no_1003_entry() -> None:
    """Alarm 16 sends 0x8611, never 0x5530: that word is something else (or nothing)."""
    try:
        found = decode("0x00105530")
    except DecodeError:  # in no table at all
        found = []
    assert not [m for m in found if "0x1003" in m.title]


def test_alarm_35_says_ethercat_resets_it_by_a_power_cycle_only() -> None:
    """Over EtherCAT 35 leaves the slave in INIT, where 0x6040 cannot reach it
    (docs/ethercat-coe.md "Resetting 35"): the Codes tab must not read as if a reset bit did."""
    texts = [m.text for m in decode("alarm 35")]
    assert texts and all("EtherCAT" in t and "power cycle" in t for t in texts), texts
    assert not any("power cycle" in m.text for m in decode("alarm 16"))


def test_the_0x603f_code_of_alarm_35_says_so_too() -> None:
    """A master sees 35 as its 0x603F code 0x5530 or its emergency (seed 004 ch. 5 "Codici
    allarmi specifici"), not as the number: typed into the Codes tab, both must say what
    "alarm 35" says, not read as if 0x80 on 0x6040 could clear it."""
    for typed in ("0x5530", "30 55 01 23 00 00 00 00"):
        texts = [m.text for m in decode(typed) if m.family == "Servo drive"]
        assert texts and all("power cycle" in t for t in texts), (typed, texts)
    assert not any("power cycle" in m.text for m in decode("0x8611"))
