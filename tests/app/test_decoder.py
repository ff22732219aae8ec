"""The code decoder, row by row over the devices' own tables.

Each case builds its input from the table row with the device's own encoder (emergency data,
0x5400 word, AL status code, CAN frame) and checks that the decoder names that row: the FastCAT
coupler and module codes (seed 000 §7, §7.5, §7.6, §6.23, §7.7), the ETG AL status codes
(seed 000 §7.7), the DS 301 SDO abort codes (seed 004 ch. 4), the drive alarms and their
0x603F codes (seed 004 ch. 3, ch. 5), the TRS-CAT application errors (seed 001 §9.3.7), the
CPX-E-EC emergency codes, error numbers and Text-IDs (seed 002 §2.5.2-§2.5.3) and the CANopen
node's own EMCY codes (DS 301).
"""

from __future__ import annotations

import pytest

from app.decoder import (
    CANOPEN,
    CPX,
    ETHERCAT,
    FASTCAT,
    SDO,
    SERVO,
    TRSCAT,
    DecodeError,
    Meaning,
    decode,
    register_text,
)
from devices.canopen import emcy as ds301
from devices.cpx import codes as cpx
from devices.cpx.messages import emergency_frame as cpx_frame
from devices.ethercat import AL_STATUS_CODES
from devices.events import fmt_bytes
from devices.fastcat import alarms as fastcat
from devices.od import ABORT_TEXT, AbortCode
from devices.servo import alarms as servo
from devices.trscat.diagnostics import FAULTS, check_message
from devices.trscat.diagnostics import emergency_frame as trs_frame

FASTCAT_ROWS = [row for table in fastcat.CODE_TABLES.values() for row in table.values()]
DRIVE_ROWS = {(a.code, a.name): a for bus in ("modbus", "profinet")
              for a in servo.alarm_table(bus).values()}
# The rows a drive sends as an emergency / shows in 0x603F: CANopen's and CoE's (seed 004 ch. 4,
# ch. 5); Profinet has neither (ch. 6).
CODED_ROWS = {(a.code, a.name): a for bus in servo.CODED_FIELDBUSES
              for a in servo.alarm_table(bus).values()}


def family(meanings: list[Meaning], name: str) -> list[Meaning]:
    return [m for m in meanings if m.family == name]


def one(meanings: list[Meaning], name: str) -> Meaning:
    found = family(meanings, name)
    assert len(found) == 1, f"{name}: {meanings}"
    return found[0]


# ---- the examples of the brief, as a technician pastes them ----------------------------------
@pytest.mark.parametrize(("text", "fam", "words"), [
    ("FF00 81 02 00 00 04 00", FASTCAT, ["0x04 MISSING_NODE_ANSWER", "module 2"]),
    ("ff00, 81, 02 00 00 04 00", FASTCAT, ["MISSING_NODE_ANSWER", "module 2"]),
    ("'Box 1 (FastCAT)' (1001): CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00').", FASTCAT,
     ["MISSING_NODE_ANSWER"]),
    ("0xFF00 0x81 02 00 00 04 00", FASTCAT, ["MISSING_NODE_ANSWER"]),
    ("00 FF 81 02 00 00 04 00", FASTCAT, ["MISSING_NODE_ANSWER", "module 2"]),  # CAN frame
    ("0x8204", FASTCAT, ["module 2", "coupler code 0x04 MISSING_NODE_ANSWER"]),
    ("AL Status Code '0x8204'", FASTCAT, ["module 2"]),
    ("0x0052", ETHERCAT, ["unexpected device"]),
    ("0x06020000", SDO, ["Object does not exist"]),
    ("8130", CANOPEN, ["Life guard or heartbeat error"]),
    ("0x8611", SERVO, ["Alarm 16 FOLLOWING_ERROR"]),
    ("alarm 16", SERVO, ["FOLLOWING_ERROR", "0x8611"]),
    ("0x04000002", FASTCAT, ["0x04 MISSING_NODE_ANSWER", "module 2"]),
])
def test_examples(text: str, fam: str, words: list[str]) -> None:
    found = family(decode(text), fam)
    assert found, decode(text)
    assert all(w in found[0].title + " " + found[0].text for w in words), found[0]


# ---- FastCAT (seed 000 §7, §7.5, §7.6, §6.23, §7.7) ----------------------------------------
@pytest.mark.parametrize("row", FASTCAT_ROWS, ids=lambda r: r.label)
def test_fastcat_emergency_names_the_row_and_the_module(row: fastcat.AlarmCode) -> None:
    data = fastcat.emergency_data(row.table, row.code, 5)
    text = f"{fastcat.EMERGENCY_CODE:04X} {fastcat.EMERGENCY_REGISTER:02X} {fmt_bytes(data)}"
    m = one(decode(text), FASTCAT)
    assert f"{row.table.capitalize()} alarm 0x{row.code:02X} {row.symbol} on module 5" in m.text
    assert row.description in m.text
    assert ("§7.5" if row.table == fastcat.COUPLER else "§7.6") in m.source
    assert "Error register 0x81 (seed 000 §7): device error" in m.text


@pytest.mark.parametrize("row", FASTCAT_ROWS, ids=lambda r: r.label)
def test_fastcat_0x5400_word(row: fastcat.AlarmCode) -> None:
    word = fastcat.Alarm(row.table, row.code, 3).word
    m = one(decode(f"0x{word:08X}"), FASTCAT)
    assert f"0x{row.code:02X} {row.symbol} on module 3" in m.text and "§6.23" in m.source


@pytest.mark.parametrize("row", list(fastcat.COUPLER_CODES.values()), ids=lambda r: r.label)
@pytest.mark.parametrize("module", [0, 1, 16])
def test_fastcat_manufacturer_al_status(row: fastcat.AlarmCode, module: int) -> None:
    code = fastcat.manufacturer_al_status(row.table, row.code, module)
    m = one(decode(f"0x{code:04X}"), FASTCAT)
    where = f"module {module}" if module else "the coupler itself (module 0)"
    assert f"{where}, coupler code 0x{row.code:02X} {row.symbol}" in m.text


def test_a_fastcat_module_alarm_has_no_al_status_code() -> None:
    """§7.7 carries coupler alarms only: 0x8700 (byte 0 = 0) is no FastCAT reading."""
    assert fastcat.manufacturer_al_status(fastcat.MODULE, 0x0B, 7) is None
    assert family(decode("0x8700"), FASTCAT) == []


@pytest.mark.parametrize("row", FASTCAT_ROWS, ids=lambda r: r.label)
def test_fastcat_symbol_and_label(row: fastcat.AlarmCode) -> None:
    for text in (row.label, "CO_E_" + row.symbol):
        found = family(decode(text), FASTCAT)
        assert any(row.symbol in m.text and row.description in m.text for m in found)


def test_a_bare_fastcat_code_reads_in_both_tables() -> None:
    """§7.5 / §7.6 both number from 0x01: 0x04 is MISSING_NODE_ANSWER and ALARM_IO_FAULT."""
    texts = " ".join(m.text for m in family(decode("0x04"), FASTCAT))
    assert "MISSING_NODE_ANSWER" in texts and "ALARM_IO_FAULT" in texts


# ---- EtherCAT AL status codes (seed 000 §7.7) ------------------------------------------------
@pytest.mark.parametrize("code", sorted(AL_STATUS_CODES), ids=lambda c: f"0x{c:04X}")
def test_al_status_codes(code: int) -> None:
    m = one(decode(f"0x{code:04X}"), ETHERCAT)
    assert m.text.rstrip(".") == AL_STATUS_CODES[code].rstrip(".") and m.source == "seed 000 §7.7"


# ---- SDO aborts (DS 301, seed 004 ch. 4) -----------------------------------------------------
@pytest.mark.parametrize("code", list(AbortCode), ids=lambda c: c.name)
def test_sdo_abort_codes(code: AbortCode) -> None:
    m = one(decode(f"0x{int(code):08X}"), SDO)
    assert m.text.rstrip(".") == ABORT_TEXT[code].rstrip(".")
    frame = bytes((0x80, 0x00, 0x54, 0x00)) + int(code).to_bytes(4, "little")
    framed = one(decode(fmt_bytes(frame)), SDO)
    assert "object 0x5400:00" in framed.title and framed.text == m.text


# ---- servo drive (seed 004 ch. 3, ch. 5) -----------------------------------------------------
@pytest.mark.parametrize("alarm", list(CODED_ROWS.values()), ids=lambda a: f"{a.code}-{a.name}")
def test_drive_emergency_with_its_alarm_number(alarm: servo.AlarmSpec) -> None:
    """The drive sends its alarm's 0x603F code with the alarm number in the first vendor byte
    (devices/canopen/emcy.py): the decoder names exactly that alarm."""
    code = alarm.error_code_or_generic
    frame = ds301.payload(code, ds301.register_bits(code), bytes((alarm.code,)))
    found = family(decode(fmt_bytes(frame)), SERVO)
    assert found and all(f"Alarm {alarm.code} " in m.text for m in found)
    assert any(alarm.name in m.text for m in found)


@pytest.mark.parametrize("alarm", list(DRIVE_ROWS.values()), ids=lambda a: f"{a.code}-{a.name}")
def test_drive_alarm_by_number_and_name(alarm: servo.AlarmSpec) -> None:
    for text in (f"alarm {alarm.code}", alarm.name):
        found = family(decode(text), SERVO)
        assert any(m.title == f"Drive alarm {alarm.code} {alarm.name}" for m in found)
    if (alarm.code, alarm.name) not in CODED_ROWS:
        return  # a Profinet-only meaning: no 0x603F code (test_decoder_seed_rows.py)
    code = alarm.error_code_or_generic
    assert any(alarm.name in m.text for m in family(decode(f"0x{code:04X}"), SERVO))


def test_an_unknown_drive_alarm_number() -> None:
    with pytest.raises(DecodeError, match="no alarm 99"):
        decode("alarm 99")


# ---- TRS-CAT (seed 001 §9.3.7) ---------------------------------------------------------------
@pytest.mark.parametrize("fault", list(FAULTS.values()), ids=lambda f: f.name)
def test_trscat_emergency(fault) -> None:
    found = family(decode(fmt_bytes(trs_frame(fault, 2, fault.register))), TRSCAT)
    assert any(m.text.startswith(fault.text + " (slot 2)") for m in found)
    shutdown = next(m for m in found if m.text.startswith(fault.text))
    assert ("TRS bus shuts down" in shutdown.text) == fault.bus_shutdown
    assert any(m.text.startswith(fault.text) for m in family(decode(fault.name), TRSCAT))
    diag = family(decode(f"0xE800{fault.code:04X}"), TRSCAT)  # ETG.1020 Diag Code
    assert any(m.text.startswith(fault.text) for m in diag)


# ---- CPX-E-EC (seed 002 §2.5.2 Tab. 16-17, §2.5.3 Tab. 20-23) --------------------------------
@pytest.mark.parametrize("cause", list(cpx.CAUSES.values()), ids=lambda c: c.name)
def test_cpx_emergency_frame(cause: cpx.Cause) -> None:
    code = cpx.emcy_code_for(cause)
    bits = cause.error.error_bit | (cause.module_bit or cpx.ST_OUTPUT)
    frame = cpx_frame(code, cpx.REG_GENERIC | cause.register_bit, bits, 4, cause.cpx_error, 0)
    m = one(decode(fmt_bytes(frame)), CPX)
    assert m.text.startswith(cpx.EMCY_CODES[code])
    assert f"Module 4, {cause.error.text}" in m.text
    assert all(cpx.STATUS_BITS[b] in m.text for b in range(8) if bits >> b & 1)


def test_cpx_emergency_byte_7_is_decoded() -> None:
    """Tab. 20 / Tab. 26: byte 7 is the additional information, e.g. the number of the first
    faulty channel: a wire break on channel 1 of module 3 (48 03 03 00 01) named the module
    and the error but left the channel out."""
    frame = cpx_frame(cpx.EMCY_LOAD_DUMP, 0x81, 0x48, 3, 3, 1)
    m = one(decode(fmt_bytes(frame)), CPX)
    assert "byte 7 = 1 (additional information, e.g. the first faulty channel)" in m.text


@pytest.mark.parametrize("code", sorted(cpx.EMCY_CODES), ids=lambda c: f"0x{c:04X}")
def test_cpx_emcy_codes(code: int) -> None:
    assert one(decode(f"0x{code:04X}"), CPX).text.startswith(cpx.EMCY_CODES[code])


@pytest.mark.parametrize("error", list(cpx.CPX_ERRORS.values()), ids=lambda e: e.symbol)
def test_cpx_error_numbers(error: cpx.CpxError) -> None:
    for text in (f"0x{error.text_id:04X}", error.symbol,
                 f"0x{cpx.diag_code(cpx.DIAG_CODE_CPX, error.number):08X}"):
        m = one(decode(text), CPX)
        assert f"CPX error number {error.number}" in m.title and error.text in m.text


@pytest.mark.parametrize("text_id", sorted(cpx.TEXT_IDS), ids=lambda c: f"0x{c:04X}")
def test_cpx_text_ids(text_id: int) -> None:
    assert one(decode(f"0x{text_id:04X}"), CPX).text.startswith(cpx.TEXT_IDS[text_id][1])


# ---- CANopen node (DS 301) -------------------------------------------------------------------
@pytest.mark.parametrize("code", [ds301.ERROR_RESET, ds301.LIFE_GUARD_ERROR,
                                  ds301.PDO_LENGTH_ERROR], ids=lambda c: f"0x{c:04X}")
def test_canopen_node_codes(code: int) -> None:
    frame = ds301.payload(code, ds301.register_bits(code))
    assert family(decode(fmt_bytes(frame)), CANOPEN)


@pytest.mark.parametrize(("code", "bits"), [(0x2999, "Current"), (0x3999, "Voltage"),
                                            (0x4999, "Temperature"),
                                            (0x8199, "Communication Error"),
                                            (0x8999, "Device Profile Specific"),
                                            (0xFF99, "Manufacturer Specific"),
                                            (0x5555, "Generic Error")])
def test_an_unknown_emcy_code_gets_its_register_bits(code: int, bits: str) -> None:
    """The class by the high byte: tests/app/test_decoder_tables.py."""
    assert bits in one(decode(f"0x{code:04X}"), CANOPEN).text.split("error register bits")[1]


def test_register_bits() -> None:
    assert register_text(0x81) == "0x81: Generic Error, Manufacturer Specific"  # seed 004 ch. 4
    assert register_text(0x00) == "0x00: no error"


# ---- what is not a code ----------------------------------------------------------------------
@pytest.mark.parametrize("text", ["", "   ", "hello world", "FF 00 zz", "0x123456789",
                                  "NOT_AN_ALARM", "FF00 81 0102"])
def test_not_a_code(text: str) -> None:
    with pytest.raises(DecodeError):
        decode(text)


@pytest.mark.parametrize("code", [0x0017, 0x001A, 0x0035], ids=lambda c: f"0x{c:04X}")
def test_trscat_check_message_diag_code(code: int) -> None:
    """Seed 001 §9.3.7: a refused SM / DC check is a 0x10F3 message whose Diag Code holds the
    AL status code in the manufacturer area (devices/trscat/diagnostics.check_message)."""
    diag = check_message(code, "check", 0).diag_code
    m = one(decode(f"0x{diag:08X}"), TRSCAT)
    assert m.text.rstrip(".") == AL_STATUS_CODES[code].rstrip(".")


def test_a_bare_decimal_number_also_reads_as_the_drive_alarm() -> None:
    """The UI audit: "16" decoded as AL status 0x0016 only, while the drive's display shows
    its alarms in decimal (seed 004 ch. 5) and alarm 16 is what many users mean. Every table
    the number reads in is listed, each under its family."""
    found = decode("16")
    families = [m.family for m in found]
    assert ETHERCAT in families and SERVO in families, found
    drive = next(m for m in found if m.family == SERVO)
    assert drive.title.startswith("Drive alarm 16 ") and "FOLLOWING_ERROR" in drive.title
    assert [m.family for m in decode("0x16")] == [ETHERCAT]  # hex written as hex: no decimal
    assert SERVO not in [m.family for m in decode("1A")]


def test_the_codes_tab_names_each_table_a_number_reads_in() -> None:
    from app.ui.panels.decoder import result_html

    html = result_html("16", decode("16"))
    assert "2 readings" in html and ETHERCAT in html and SERVO in html
    assert html.index(ETHERCAT) < html.index("AL status code 0x0016")
