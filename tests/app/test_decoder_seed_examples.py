"""The seeds' own worked examples, pasted into the Codes tab as a trainee copies them.

The seeds print emergencies, log lines and diagnosis messages byte for byte: the FastCAT
emergency in the TwinCAT, Sirio, Pegaso and AITracePrint displays (seed 000 §7.1-§7.4) and in
the §7.7 log, the CPX-E-EC's 0x10F3 message (seed 002 Tab. 15/16), the drive's Modbus exception
(seed 004 ch. 2 "Eccezioni"). The master renders its log in the same four styles
(devices/master/log_styles.py), so whatever its log shows must decode too, byte order and all.
Before, only the TwinCAT line as FieldRig prints it decoded: the seed's own §7.1 line (its
quotes round '02 00 00 04') lost its data bytes, and every Sirio, Pegaso and AITracePrint line,
the §7.7 "abnormal state change ... with code 0x8204" line, the Tab. 15 message and "83 02"
were refused.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import viser

from app.decoder import (
    CANOPEN,
    CPX,
    ETHERCAT,
    FASTCAT,
    MODBUS,
    SDO,
    SERVO,
    TRSCAT,
    DecodeError,
    Meaning,
    decode,
)
from app.screenshots import free_port
from app.ui.panels.decoder import DecoderPanel, reported_code
from devices.events import AlarmChanged
from devices.master.log_styles import STYLES, Entry, render
from devices.trscat.diagnostics import FAULTS, app_message

COUPLER = bytes.fromhex("0200000400")  # §7.2 / §7.3 first example: coupler error 04, node 2
MODULE = bytes.fromhex("02000B0000")  # second example: module 2 reports 0B (not calibrated)
COUPLER_WORDS = ["0x04 MISSING_NODE_ANSWER", "module 2"]
MODULE_WORDS = ["0x0B TARATURA", "module 2"]


def fastcat(text: str) -> Meaning:
    found = [m for m in decode(text) if m.family == FASTCAT]
    assert len(found) == 1, decode(text)
    return found[0]


def says(m: Meaning, words: list[str]) -> bool:
    return all(w in f"{m.title} {m.text}" for w in words)


# ---- seed 000 §7.1-§7.4, §7.7: the lines as the seed prints them ------------------------------
SIRIO_COUPLER = ("Emergency\tReset\tByte 0 basso\tByte 3 alto\n"
                 "Err. Code\tFF00\tAdditional Code\t\n"
                 "Err. Reg.\t0081\t0x low 02 00 00 04 00 high\t")
SIRIO_MODULE = ("Emergency\tReset\tByte 0\tByte 2\n"
                "Err. Code\tFF00\tAdditional Code\t\n"
                "Err. Reg.\t0081\t0x low 02 00 0B 00 00 high\t")
PEGASO_COUPLER = "ERR CODE\t[0xFF00]\nERR REG\tByte 3 [0x81] Byte 0\n" \
                 "ERR DATA\talto [0x00 04 00 00 02] basso"
PEGASO_MODULE = "ERR CODE\t[0xFF00]\nERR REG\tByte 2 [0x81] Byte 0\n" \
                "ERR DATA\t[0x00 00 0B 00 02] basso"


@pytest.mark.parametrize(("text", "words"), [
    # §7.1, as printed: the data bytes in quotes ('02 00 00 04'00')
    ("(65535)\t05/07/2019 11.48.41 438 ms\t'Box 1 (FastCat)' (1001): CoE - Emergency "
     "(Hex: ff00, 81, '02 00 00 04'00').", COUPLER_WORDS),
    # §7.2 Sirio, with and without the line breaks (a text box drops them on paste)
    (SIRIO_COUPLER, COUPLER_WORDS),
    (SIRIO_COUPLER.replace("\n", ""), COUPLER_WORDS),
    (SIRIO_MODULE, MODULE_WORDS),
    # §7.3 Pegaso: the data high byte first
    (PEGASO_COUPLER, COUPLER_WORDS),
    (PEGASO_COUPLER.replace("\n", ""), COUPLER_WORDS),
    (PEGASO_MODULE, MODULE_WORDS),
    # §7.4 AITracePrint: 33540 is the AL status code 0x8304 in decimal, module 3 "did not
    # answer" (coupler code 0x04, the reading of the State tab)
    ("380808 - 00000001 - ** ECAT: EcatManagerSlaveStateCallback: 11 2 33540:Unknown",
     ["0x8304", "module 3", "0x04 MISSING_NODE_ANSWER"]),
    # §7.7 TwinCAT log, the abnormal state change and the failed transition
    ("(65535)\t12/11/2019 14.51.30 280 ms\t'Box 1 (FastCAT)' (1001): abnormal state change "
     "(from 'OP' to 'PREOP') with code 0x8204. Try to go back to 'OP'...",
     ["0x8204", "module 2", "0x04 MISSING_NODE_ANSWER"]),
    ("'Box 1 (FastCAT)' (1001): 'PREOP to SAFEOP' failed! Error: 'check device state for "
     "SAFEOP'. AL Status '0x0012' read and '0x0004' expected. AL Status Code '0x8204'",
     ["0x8204", "module 2"]),
])
def test_the_seed_000_lines(text: str, words: list[str]) -> None:
    m = fastcat(text)
    assert says(m, words), m


def test_the_74_emergency_line_names_its_bytes_in_the_printed_order() -> None:
    """§7.4 prints data=0x0300002400 for "module 3 reports 04": byte 0 (the module) first, as
    the master's aitraceprint style renders it; byte 3 = 0x24 is in neither table, and the
    decoder says so for module 3 instead of inventing a code."""
    m = fastcat("380856 - 00000001 - ECAT_EVENT Emergency slave = 11 emcyCode = 0xFF00 "
                "emcyReg = 0x81 data=0x0300002400")
    assert says(m, ["module 3", "0x24"]) and "not in the seed's tables" in m.text, m


# ---- whatever the master's log shows, in every style ------------------------------------------
def emergency(data: bytes) -> Entry:
    return Entry(0, "emergency", {"code": 0xFF00, "register": 0x81, "data": data},
                 slave="Box 1 (FastCAT)", address=1001, position=1)


@pytest.mark.parametrize("style", STYLES)
@pytest.mark.parametrize(("data", "words"), [(COUPLER, COUPLER_WORDS), (MODULE, MODULE_WORDS)])
def test_every_log_style_decodes(style: str, data: bytes, words: list[str]) -> None:
    text = render(style, emergency(data))
    assert says(fastcat(text), words)
    assert says(fastcat(text.replace("\n", " ")), words)


@pytest.mark.parametrize("style", STYLES)
def test_every_style_of_the_abnormal_state_change_decodes(style: str) -> None:
    entry = Entry(0, "abnormal", {"from_state": "OP", "to_state": "PREOP", "code": 0x8204,
                                  "target": "OP"}, slave="Box 1 (FastCAT)", address=1001,
                  position=1)
    text = render(style, entry)
    assert says(fastcat(text.replace("\n", " ")), ["module 2", "MISSING_NODE_ANSWER"]), text


# ---- seed 002 Tab. 15 / 16: the 0x10F3 diagnosis message ---------------------------------------
TAB_15 = "02 00 00 E1\t02 02\t02 - 37\t1F C5 9D 61 31 00 00-00\t05 00\t02\t05 00\t80"


@pytest.mark.parametrize("text", [TAB_15, TAB_15.replace("-", " "), TAB_15 + " 00"])
def test_the_tab_15_message(text: str) -> None:
    found = [m for m in decode(text) if m.family == CPX]
    joined = " ".join(f"{m.title} {m.text}" for m in found)
    for words in ("0xE1000002", "CPX error number 2", "Short circuit", "error message",
                  "Text-ID 0x3702", "module 2", "0x80"):
        assert words in joined, found


def test_the_tab_15_diag_code_as_printed() -> None:
    """Tab. 16 prints the Diag Code as its bytes, low first: 02 00 00 E1 = 0xE1000002."""
    found = [m for m in decode("02 00 00 E1") if m.family == CPX]
    assert found and "0xE1000002" in found[0].title and "Short circuit" in found[0].text


def test_a_trscat_message_as_its_tab_shows_the_bytes() -> None:
    """Seed 001 §9.3.7: the TRS-CAT's message (its snapshot's "bytes") decodes to the fault."""
    fault = FAULTS["FIELD_SUPPLY"]  # 0x3220, +24 V field supply, on slot 3
    raw = app_message(fault, 3, 1_500_000_000).encode().hex(" ").upper()
    found = [m for m in decode(raw) if m.family == TRSCAT]
    assert found and any(m.text.startswith(fault.text) for m in found), decode(raw)


# ---- seed 004 ch. 2 "Eccezioni": the drive's Modbus exception ----------------------------------
@pytest.mark.parametrize("text", ["83 02", "0x83 0x02", "05 83 02"])
def test_the_drives_exception_02(text: str) -> None:
    (m,) = [m for m in decode(text) if m.family == MODBUS]
    assert "02 Illegal Data Address" in m.text and "0x03" in m.title, m


def test_two_bytes_with_no_exception_code_are_no_modbus_exception() -> None:
    """An emergency code typed as its two bytes (FF 00) read as 'Modbus exception 00'."""
    with pytest.raises(DecodeError, match="bytes not understood"):
        decode("FF 00")


def test_an_exception_the_drive_never_sends() -> None:
    (m,) = [m for m in decode("86 01") if m.family == MODBUS]
    assert "01 Illegal Function" in m.text and "never" in m.text, m


@pytest.mark.parametrize("text", ["81 02", "05 84 02", "0x8F 0x02"])
def test_exception_02_to_a_function_the_drive_does_not_implement(text: str) -> None:
    """Ch. 2 "Codici funzione": the drive implements 03, 06 and 16 only (their error codes
    0x83, 0x86, 0x90) and drops any other request without a reply ("Eccezioni"): an 02 to
    function 01, 04 or 15 came from another server, not from the drive."""
    (m,) = [m for m in decode(text) if m.family == MODBUS]
    assert "02 Illegal Data Address" in m.text, m
    assert "never" in m.text and "03, 06 and 16" in m.text, m
    assert "the only exception the drive answers" not in m.text, m


@pytest.mark.parametrize("text", ["83 02", "86 02", "90 02"])
def test_exception_02_to_an_implemented_function_is_the_drive_s(text: str) -> None:
    (m,) = [m for m in decode(text) if m.family == MODBUS]
    assert "the only exception the drive answers" in m.text and "never" not in m.text, m


# ---- malformed input: one clear message -------------------------------------------------------
@pytest.mark.parametrize(("text", "hint"), [
    ("Err. Reg.\t0081\t0x low 02 00 00 04 00 high", "Err. Code"),
    ("ERR DATA\talto [0x00 04 00 00 02] basso", "ERR CODE"),
    ("83 0F", "exception"),
    # §7.4's other lines: the PLC's own, which the seed does not explain
    ("380808 - 00000001 - !! ECAT_EVENT ErrorControl slave = 11 errorLocCode = 10071",
     "errorLocCode is the PLC.s"),
    ("213064 - 00000100 - !!! Alarm 77:4 Date:22/1 Time:9:48:40", "PLC alarm"),
])
def test_a_line_without_its_code_says_what_is_missing(text: str, hint: str) -> None:
    with pytest.raises(DecodeError, match=hint):
        decode(text)


# ---- the Codes tab itself, through its callback -----------------------------------------------
class _Runtime:
    def events_since(self, seq: int) -> tuple[int, list[object]]:
        return seq, []


@pytest.fixture
def panel() -> Iterator[DecoderPanel]:
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        yield DecoderPanel(server, _Runtime())  # type: ignore[arg-type]
    finally:
        server.stop()


def test_the_codes_tab_decodes_a_pasted_pegaso_display(panel: DecoderPanel) -> None:
    panel.show(PEGASO_COUPLER.replace("\n", ""))  # what a click on Decode runs
    html = panel.result_for(None)  # a page's that has typed and picked nothing
    assert "MISSING_NODE_ANSWER" in html and "module 2" in html, html


def test_the_sirio_register_typed_as_the_display_shows_it() -> None:
    """§7.2 prints the error register in four digits (Err. Reg. 0081)."""
    assert says(fastcat("FF00 0081 02 00 00 04 00"), COUPLER_WORDS)
    with pytest.raises(DecodeError):
        decode("FF00 0181 02 00 00 04 00")  # no register is two bytes


def test_the_start_of_the_manufacturer_area() -> None:
    """§7.7 ends its table with 0x8000 "Inizio dell'area manufacturer"."""
    found = [m for m in decode("0x8000") if m.family == ETHERCAT]
    assert found and "manufacturer" in found[0].text.lower(), decode("0x8000")


# ---- FieldRig's own lines: the event log and the CAN monitor ----------------------------------
@pytest.mark.parametrize(("text", "fam", "words"), [
    ("Emergency sent (code 0xFF00, register 0x81, data 02 00 00 04 00)", FASTCAT,
     COUPLER_WORDS),
    ("alarm 0x0B TARATURA module 2 raised", FASTCAT, ["0x0B TARATURA"]),
    ("alarm 16 FOLLOWING_ERROR raised", SERVO, ["FOLLOWING_ERROR", "0x8611"]),
    ("alarm 0xA000 CONFIG_ERROR raised", TRSCAT, ["Configuration error"]),
    ("alarm 0x3702 SHORT_CIRCUIT module 2 raised", CPX, ["Short circuit"]),
    ("node 2: code 0x8611, register 0x21, data 10 00 00 00 00", SERVO, ["Alarm 16"]),
    ("node 2: error reset, register 0x00, data 00 00 00 00 00", CANOPEN, ["Error reset"]),
    ("node 2 ->: abort 0x6041:00 0x06090011 (Sub-index does not exist)", SDO,
     ["0x06090011 on object 0x6041:00", "Sub-index does not exist"]),
    # the CPX-E-EC's own log line of a 0x10F3 message (DiagMessage.text)
    ("0x10F3: error [CPX 0xE1000002] CPX error 2: Short circuit/overload (2, 0x80)", CPX,
     ["0xE1000002", "Short circuit"]),
    # the FastCAT's refused reset (devices/fastcat/faults.py)
    ("Reset fault refused: alarm 0x04 MISSING_NODE_ANSWER module 2, cause still present",
     FASTCAT, COUPLER_WORDS),
    # the master's log (devices/master/log_styles.py "identity_read", "init_command")
    ("'Box 4 (drive_ec)' (1004): identity check failed: SDO upload 0x1018:01 aborted with "
     "0x06020000.", SDO, ["0x06020000 on object 0x1018:01", "Object does not exist"]),
    ("'Box 4 (drive_ec)' (1004): init command 'set mode' (PS) failed: SDO download "
     "0x6060:00 aborted with 0x06090030.", SDO, ["0x06090030 on object 0x6060:00"]),
])
def test_fieldrigs_own_lines(text: str, fam: str, words: list[str]) -> None:
    found = [m for m in decode(text) if m.family == fam]
    assert found and says(found[0], words), decode(text)


# ---- a reported alarm reads in its own device's table -----------------------------------------
@pytest.mark.parametrize(("event", "fam", "words"), [
    (AlarmChanged(0, "cpx", code="0x3708", name="UNDERVOLTAGE", module=2), CPX,
     "CPX error number 8"),
    (AlarmChanged(0, "drive", code="5", name="UNDERVOLTAGE"), SERVO, "Drive alarm 5"),
    (AlarmChanged(0, "fastcat", code="0x0B", name="TARATURA", module=2), FASTCAT,
     "0x0B TARATURA"),
])
def test_a_picked_alarm_reads_only_in_its_table(event: AlarmChanged, fam: str,
                                                 words: str) -> None:
    """UNDERVOLTAGE is drive alarm 5 and CPX error 8: picking the CPX-E-EC's alarm under
    Reported showed "Servo drive: DC power bus voltage below the minimum" first. The alarm's
    code (as the event log prints it) says which table it is from."""
    found = reported_code(event)
    assert found is not None
    meanings = decode(found[1])
    assert [m.family for m in meanings] == [fam], meanings
    assert words in meanings[0].title + " " + meanings[0].text
    line = f"alarm {event.code} {event.name} raised"  # the Event log's line
    assert [m.family for m in decode(line)] == [fam]


@pytest.mark.parametrize(("text", "hint"), [
    ("'Box 1 (FastCAT)' (1001): CoE - Emergency (Hex: ).", "nothing to decode"),
    (",", "nothing to decode"),  # separators only: an IndexError before
    ("Hex: ; )", "nothing to decode"),
    ("FF00 81 02 00 00 04 00 00 00", "five data bytes"),
])
def test_an_empty_or_overlong_emergency_is_refused(text: str, hint: str) -> None:
    """An emptied TwinCAT line crashed the decoder (IndexError); seven data bytes read as an
    emergency, which has five (seed 000 §7, seed 004 ch. 4)."""
    with pytest.raises(DecodeError, match=hint):
        decode(text)


@pytest.mark.parametrize("text", ["Err. Code\tFF00\tAdditional Code", "ERR CODE\t[0xFF00]"])
def test_the_code_row_of_a_display_alone_reads_as_the_code(text: str) -> None:
    assert decode(text) == decode("0xFF00")


def test_a_resettable_fastcat_alarm_names_both_resets() -> None:
    """§7: "Il reset degli emergency resettabili avviene alzando il bit di Reset Fault ...
    oppure comandando un resync della linea ethercat": the Codes tab named Reset fault only."""
    text = fastcat("FF00 81 02 00 00 04 00").text
    assert "Reset fault (0x5200:1)" in text and "resync" in text, text


def test_a_picked_module_alarm_keeps_its_module() -> None:
    """The event log prints "alarm 0x0B TARATURA module 2 raised"; the Reported pick of that
    alarm decoded the bare row, without the module the alarm is about."""
    event = AlarmChanged(0, "fastcat", code="0x0B", name="TARATURA", module=2)
    found = reported_code(event)
    assert found is not None and "module 2" in found[1]
    (m,) = decode(found[1])
    assert "TARATURA on module 2" in m.text, m
    (m,) = decode("alarm 0x0B TARATURA module 2 raised")
    assert "TARATURA on module 2" in m.text, m


def test_the_failed_transition_line_reads_its_al_status_register_values() -> None:
    """§7.7: "AL Status '0x0012' read and '0x0004' expected" are AL status *register* values
    (0x0130: the state, bit 4 the error flag), not AL status codes: 0x0012 is PREOP with the
    error flag, 0x0004 SAFEOP. The Codes tab read only the code of the line."""
    found = decode("'Box 1 (FastCAT)' (1001): 'PREOP to SAFEOP' failed! Error: 'check device "
                   "state for SAFEOP'. AL Status '0x0012' read and '0x0004' expected. AL "
                   "Status Code '0x8204'")
    assert says(found[0], ["0x8204", "module 2"])
    (register,) = [m for m in found if "0x0130" in m.title]
    assert "0x0012 = PREOP with the error flag" in register.text, register
    assert "0x0004 = SAFEOP" in register.text, register


@pytest.mark.parametrize("text", [
    "Err. Code FF00 Err. Reg. 0081 0x low 0 2 00 high",
    "ERR CODE [0xFF00] ERR REG [0x81] ERR DATA [0x0 04 00 00 02] basso",
    "code 0xFF00, register 0x81, data 0",
])
def test_a_display_with_half_a_byte_gets_a_message_not_a_crash(text: str) -> None:
    with pytest.raises(DecodeError, match="whole bytes"):
        decode(text)
