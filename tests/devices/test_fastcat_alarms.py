"""FastCAT alarm tables, emergency layout and 0x80XX codes (seed 000 §7, §7.1-§7.7, §6.19)."""

from __future__ import annotations

import pytest

from devices.device import CommandError
from devices.fastcat.alarms import (
    COUPLER,
    COUPLER_CODES,
    EMERGENCY_CODE,
    EMERGENCY_REGISTER,
    MODULE,
    MODULE_CODES,
    Alarm,
    by_name,
    emergency_data,
    emergency_word,
    is_resettable,
    lookup,
    manufacturer_al_status,
    parse_fault,
)

# §7.5 as printed: byte-3 code -> CO_E_ symbol.
SEED_COUPLER = {
    0x01: "MODULE_CHANGED", 0x02: "MODULE_NO_PRES", 0x03: "UNKNOWN_NODE_ANSWER",
    0x04: "MISSING_NODE_ANSWER", 0x05: "CRC_PDORX", 0x06: "CRC_PDOSDORX", 0x07: "CRC_SDO_RD",
    0x08: "CRC_SDO_WR", 0x09: "ADDRES_NOT_OK", 0x0A: "UNKNOWN_SDO_RD_ANSWER",
    0x0B: "UNKNOWN_SDO_WR_ANSWER", 0x0C: "SDO_ERROR", 0x0D: "TMO_SDORD", 0x0E: "TMO_SDOWR",
    0x0F: "FIRMW_MAST_NOTOK", 0x10: "NO_MOD", 0x11: "SAVE_FLASH",
    0x12: "ADDRESS_MASTER_NOT_OK", 0x13: "LINK_LOSS", 0x14: "SLOT_NOT_MATCHING",
    0x15: "MAX_ANALOG_MODULES",
}
# §7.6 as printed; 0x10..0x15 (AX2) have no symbol in the seed: FieldRig names.
SEED_MODULE = {
    0x01: "EMICY_MASTER", 0x02: "IOFAULT", 0x03: "ALARM_10V", 0x04: "ALARM_IO_FAULT",
    0x05: "TIMEOUT_SYNC", 0x06: "TIMEOUT_RX", 0x07: "CRC", 0x08: "UNKNOWN_CMD",
    0x09: "UNKNOWN_SDO_CMD", 0x0A: "NO_SYNC", 0x0B: "TARATURA", 0x0C: "LOW_VOLTAGE",
    0x0D: "BAD_GAIN", 0x0E: "BAD_CODEID",
}
FIELDRIG_MODULE = {0x10: "ENC1_COUNT", 0x11: "ENC2_COUNT", 0x12: "ENC1_SIGNAL",
                   0x13: "ENC2_SIGNAL", 0x14: "ENC1_ZERO_CYCLE", 0x15: "ENC2_ZERO_CYCLE"}


def test_tables_hold_exactly_the_seed_codes() -> None:
    """§7.5 numbers 0x01..0x15; §7.6 numbers 0x01..0x0E and 0x10..0x15 (no 0x0F)."""
    assert sorted(COUPLER_CODES) == sorted(SEED_COUPLER)
    assert sorted(MODULE_CODES) == sorted({**SEED_MODULE, **FIELDRIG_MODULE})


@pytest.mark.parametrize(("code", "symbol"), sorted(SEED_COUPLER.items()))
def test_coupler_row(code: int, symbol: str) -> None:
    """§7.5: symbol without CO_E_, a description, resettable iff code <= 0x7F."""
    row = COUPLER_CODES[code]
    assert (row.table, row.code, row.symbol, row.symbol_printed) == (COUPLER, code, symbol, True)
    assert len(row.description) > 10
    assert row.resettable is (code <= 0x7F)
    assert by_name(symbol) is row
    assert by_name(f"co_e_{symbol.lower()}") is row
    assert parse_fault(symbol) is row
    assert parse_fault(f"coupler:0x{code:02X}") is row
    assert parse_fault(f"coupler:{code}") is row
    assert lookup(COUPLER, code) is row


@pytest.mark.parametrize(("code", "symbol"), sorted({**SEED_MODULE, **FIELDRIG_MODULE}.items()))
def test_module_row(code: int, symbol: str) -> None:
    """§7.6: every module code is resettable (the > 0x7F rule is for coupler codes)."""
    row = MODULE_CODES[code]
    assert (row.table, row.code, row.symbol) == (MODULE, code, symbol)
    assert row.symbol_printed is (code in SEED_MODULE)
    assert len(row.description) > 10
    assert row.resettable
    assert parse_fault(symbol) is row
    assert parse_fault(f"module:0x{code:02x}") is row
    assert parse_fault(f"module:{symbol}") is row


def test_descriptions_follow_the_seed_meaning() -> None:
    """Spot checks of the English renderings (§7.1, §7.2, §7.5, §7.6)."""
    assert "answer" in COUPLER_CODES[0x04].description.lower()
    assert "flash" in COUPLER_CODES[0x11].description.lower()
    assert "0x5301" in COUPLER_CODES[0x12].description
    assert "calibrated" in MODULE_CODES[0x0B].description.lower()
    assert "1.5 turns" in MODULE_CODES[0x14].description


def test_symbols_are_unique_across_tables() -> None:
    symbols = [r.symbol for r in (*COUPLER_CODES.values(), *MODULE_CODES.values())]
    assert len(symbols) == len(set(symbols))


@pytest.mark.parametrize("text", ["0x04", "4", "0x0B", "0x15", "0x0F"])
def test_bare_code_is_refused_as_ambiguous(text: str) -> None:
    with pytest.raises(CommandError, match="ambiguous"):
        parse_fault(text)


def test_bare_code_message_names_both_readings() -> None:
    with pytest.raises(CommandError) as exc:
        parse_fault("0x04")
    assert "coupler:0x04 (MISSING_NODE_ANSWER)" in str(exc.value)
    assert "module:0x04 (ALARM_IO_FAULT)" in str(exc.value)


@pytest.mark.parametrize("text", ["NOPE", "coupler:0x16", "module:0x0F", "bus:0x01",
                                  "coupler:TARATURA"])
def test_unknown_faults_are_refused(text: str) -> None:
    with pytest.raises(CommandError):
        parse_fault(text)


@pytest.mark.parametrize(("table", "code", "resettable"), [
    (COUPLER, 0x01, True), (COUPLER, 0x7F, True), (COUPLER, 0x80, False),
    (COUPLER, 0xFF, False), (MODULE, 0x15, True),
])
def test_resettable_rule(table: str, code: int, resettable: bool) -> None:
    """§7 / §7.5: coupler codes above 0x7F are not resettable, a resync is needed."""
    assert is_resettable(table, code) is resettable


def test_emergency_constants() -> None:
    """§7: ErrorCode 0xFF00 (device specific), ErrorRegister 0x81 (device error)."""
    assert (EMERGENCY_CODE, EMERGENCY_REGISTER) == (0xFF00, 0x81)


def test_coupler_emergency_layout() -> None:
    """§7.1 / §7.2: coupler error 04 on module 02 = '02 00 00 04 00' (byte 0 first)."""
    data = emergency_data(COUPLER, 0x04, 2)
    assert data == bytes.fromhex("0200000400")
    # §7.3 (Pegaso) prints the same five bytes high to low.
    assert data[::-1].hex(" ") == "00 04 00 00 02"


def test_module_emergency_layout() -> None:
    """§7.2: module 2 reports 0B (not calibrated) = '02 00 0B 00 00'."""
    data = emergency_data(MODULE, 0x0B, 2)
    assert data == bytes.fromhex("02000B0000")
    assert data[::-1].hex(" ") == "00 00 0b 00 02"  # §7.3 Pegaso, high to low


@pytest.mark.parametrize(("table", "code", "module", "word"), [
    (COUPLER, 0x12, 0, 0x1200_0000),  # §6.19: address check, 0x5400.0 = 0x12000000
    (COUPLER, 0x04, 2, 0x0400_0002),
    (MODULE, 0x0B, 2, 0x000B_0002),
    (COUPLER, 0x15, 9, 0x1500_0009),
])
def test_0x5400_is_bytes_0_to_3_little_endian(table: str, code: int, module: int,
                                                word: int) -> None:
    """§6.23 / §7: 0x5400.0 holds the first four emergency bytes."""
    assert emergency_word(emergency_data(table, code, module)) == word
    assert Alarm(table, code, module).word == word


@pytest.mark.parametrize(("table", "code", "module", "al_code"), [
    (COUPLER, 0x04, 2, 0x8204),  # §7.7 worked example
    (COUPLER, 0x04, 3, 0x8304),  # §7.4: 33540 = 0x8304 for module 3, code 04
    (COUPLER, 0x12, 0, 0x8012),
    (MODULE, 0x0B, 2, None),  # §7.7 "allarmi gravi generati dal coupler": no module codes
])
def test_manufacturer_al_status_code(table: str, code: int, module: int,
                                     al_code: int | None) -> None:
    """§7.7: 0x8000 + module number in byte 1 + coupler code in byte 0; a module alarm has
    none (docs/fastcat-coupler.md "Module alarms keep OP")."""
    assert manufacturer_al_status(table, code, module) == al_code
    assert Alarm(table, code, module).al_status_code == al_code


def test_al_status_example_of_section_7_4() -> None:
    assert manufacturer_al_status(COUPLER, 0x04, 3) == 33540


@pytest.mark.parametrize(("alarm", "refusal"), [
    (Alarm(COUPLER, 0x01, 2), 0x0052),  # mismatch: "Perform an hardware configuration"
    (Alarm(COUPLER, 0x02, 3), 0x0052),
    (Alarm(COUPLER, 0x14, 1), 0x0070),  # 0xF030 / 0xF050 disagree
    (Alarm(COUPLER, 0x04, 2), 0x8204),  # §7.7 log: PREOP to SAFEOP refused with 0x8204
    (Alarm(MODULE, 0x0B, 2), None),  # a module alarm refuses no state request
])
def test_refusal_code(alarm: Alarm, refusal: int | None) -> None:
    assert alarm.refusal_code == refusal
