"""The error register (0x1001) in each device's own seed's words.

Seed 002 Tab. 22 names the CPX-E-EC's bits (Generic Error, Current: KZS / KZA, Voltage,
Communication Error, Manufacturer specific: wire break, other error); seed 004 ch. 4 the drive's
(DS 301's table: ... Communication Error, Device Profile Specific, Manufacturer Specific); seed
000 §7 gives the FastCAT's one value, "0x81 (device error)"; seed 001 names no bits, so the
TRS-CAT's read in DS 301's. Before, every emergency's register read in one lower-case DS 301
list ("generic error, manufacturer specific"), and a 0x1001 value pasted from the Objects tab
read "no code and no alarm name".
"""

from __future__ import annotations

import pytest

from app.decoder import CPX, FASTCAT, SERVO, TRSCAT, DecodeError, Meaning, decode


def _one(found: list[Meaning], family: str) -> Meaning:
    mine = [m for m in found if m.family == family]
    assert len(mine) == 1, found
    return mine[0]


def test_a_cpx_emergency_reads_its_register_in_tab_22s_words() -> None:
    m = _one(decode("2330 83 ee 04 03 00 01"), CPX)  # bits 0, 1 and 7
    assert "Error register 0x83 (seed 002 Tab. 22): Generic Error (set with every error), " \
           "Current (KZS: short circuit/overload of the sensor supply; KZA: short " \
           "circuit/overload of the outputs), Manufacturer specific (wire break, other error)" \
           in m.text, m.text


def test_a_cpx_register_bit_tab_22_leaves_blank() -> None:
    m = _one(decode("1000 09 00 00 00 00 00"), CPX)
    assert "Generic Error (set with every error), bit 3 (\"-\" in Tab. 22)" in m.text, m.text


def test_a_drive_emergency_reads_its_register_in_seed_004s_words() -> None:
    m = _one(decode("8611 21 10 00 00 00 00"), SERVO)  # alarm 16, 0x8611: profile bit
    assert "Error register 0x21 (seed 004 ch. 4): Generic Error, Device Profile Specific" \
        in m.text, m.text


def test_a_fastcat_emergency_reads_0x81_as_seed_000_does() -> None:
    m = _one(decode("FF00 81 02 00 00 04 00"), FASTCAT)
    assert "Error register 0x81 (seed 000 §7): device error." in m.text, m.text
    assert "Generic" not in m.text, m.text


def test_a_trscat_emergency_reads_its_register_in_ds_301s_words() -> None:
    m = _one(decode("7100 03 00 00 00 00 00"), TRSCAT)
    assert "Error register 0x03 (DS 301; seed 001 names no bits): Generic Error, Current" \
        in m.text, m.text


@pytest.mark.parametrize("query", [
    "0x1001:0 = 0x83", "0x1001:0 131", "1001:00 = 131", "0x1001:0\tError Register\tU8\tro\t131",
])
def test_a_0x1001_value_reads_in_every_devices_words(query: str) -> None:
    """As the Objects tab shows it (the value in decimal, as its Value box takes it)."""
    found = decode(query)
    cpx = _one(found, CPX)
    assert cpx.title == "0x1001:0 Error register = 0x83"
    assert cpx.text.startswith("Generic Error (set with every error), Current (KZS"), cpx.text
    assert cpx.source == "seed 002 Tab. 22"
    drive = _one(found, SERVO)
    assert drive.text.startswith("Generic Error, Current, Manufacturer Specific"), drive.text
    assert drive.source == "seed 004 ch. 4"
    trscat = _one(found, TRSCAT)
    assert trscat.source == "DS 301 (seed 001 names no bits)"
    assert FASTCAT not in {m.family for m in found}  # the FastCAT has no 0x1001


def test_a_0x1001_address_alone_lists_each_devices_bits() -> None:
    cpx = _one(decode("0x1001:0"), CPX)
    assert "bit 4 Communication Error (node guard, heartbeat: other fieldbuses only)" \
        in cpx.text, cpx.text


def test_a_zero_register_reads_no_error() -> None:
    assert _one(decode("0x1001:0 0"), CPX).text.startswith("no error")


@pytest.mark.parametrize(("query", "hint"), [
    ("0x1001:0 = 0x183", "one byte"),
    ("0x1001:0 = 3 (0x05)", "two values"),
    ("0x1001:1 = 3", "sub 0"),
])
def test_a_bad_0x1001_query_is_one_message(query: str, hint: str) -> None:
    with pytest.raises(DecodeError, match=hint):
        decode(query)
