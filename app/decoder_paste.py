"""A log line or display pasted into the Codes tab, reduced to the code it carries.

The master's logger writes in the four styles of seed 000 §7.1-§7.4
(devices/master/log_styles.py) and the seeds print their examples that way, so a trainee
pastes any of them:

- TwinCAT (§7.1, §7.7): ``CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00').`` (the seed's §7.1
  line quotes the bytes: ``'02 00 00 04'00'``), ``... with code 0x8204. Try to go back ...``,
  ``AL Status Code '0x8204'``;
- Sirio (§7.2): ``Err. Code FF00`` / ``Err. Reg. 0081`` / ``0x low 02 00 00 04 00 high``
  (data byte 0 first, the register in four digits);
- Pegaso (§7.3): ``ERR CODE [0xFF00]`` / ``ERR REG Byte 3 [0x81] Byte 0`` /
  ``ERR DATA alto [0x00 04 00 00 02] basso`` (data *high byte first*);
- AITracePrint (§7.4): ``emcyCode = 0xFF00 emcyReg = 0x81 data=0x0200000400`` (byte 0 first,
  as the master renders it) and ``EcatManagerSlaveStateCallback: 11 2 33540:Unknown`` (the AL
  status code in decimal).

and FieldRig's own lines: the event log's ``Emergency sent (code 0xFF00, register 0x81, data
02 00 00 04 00)``, the CAN monitor's ``code 0x8611, register 0x21, data 10 00 00 00 00`` /
``error reset, ...`` and ``abort 0x6041:00 0x06090011 (...)`` (devices/canopen/decode.py), the
master's ``SDO upload 0x1018:01 aborted with 0x06020000``, the CPX-E-EC's 0x10F3 line
``error [CPX 0xE1000002] CPX error 2: ...`` (its Diag Code).
The event log's ``alarm 0x04 MISSING_NODE_ANSWER module 2 raised`` :func:`app.decoder.decode`
reads itself (code and name together).

A display is three lines; a text box drops the line breaks of a paste, so every pattern is
searched in the whole text. :func:`canonical` returns what :func:`app.decoder.decode` reads
(``FF00 81 02 00 00 04 00``, ``0x8204``), or the text unchanged when no pattern matches.
"""

from __future__ import annotations

import re
from dataclasses import dataclass


class PasteError(ValueError):
    """A recognised line that does not carry the code (the decoder reports the message)."""


_HEX = r"[0-9A-Fa-f]"
# The ')' may be missing: a trainee selecting up to the last byte leaves it (and "'." ) behind.
_TWINCAT_EMCY = re.compile(r"Hex:\s*([^)]*)")
_AL_QUOTED = re.compile(rf"Code\s*'(0x{_HEX}+)'")  # "AL Status Code '0x8204'"
_AL_WITH_CODE = re.compile(rf"with code\s+(0x{_HEX}+)")  # "abnormal state change ... with code"
_TRACE_CODE = re.compile(rf"emcyCode\s*=\s*0x({_HEX}+)")
_TRACE_REG = re.compile(rf"emcyReg\s*=\s*0x({_HEX}+)")
_TRACE_DATA = re.compile(rf"data\s*=\s*0x({_HEX}*)")
_TRACE_STATE = re.compile(r"EcatManagerSlaveStateCallback:\s*\d+\s+\d+\s+(\d+)\s*:")
_TRACE_CHANGE = re.compile(r"SlaveStateChange\s+slave")
_TRACE_ERROR_CONTROL = re.compile(r"ErrorControl\b.*errorLocCode")
_TRACE_PLC_ALARM = re.compile(r"!!!\s*Alarm\s+\d+:\d+")
_FIELDRIG_EMCY = re.compile(rf"(?:code\s+0x({_HEX}{{1,4}})|error reset),\s*register\s+"
                            rf"0x({_HEX}{{1,2}}),\s*data\s*([0-9A-Fa-f \t]*)")
_FIELDRIG_ABORT = re.compile(rf"\babort\s+0x({_HEX}{{4}}):({_HEX}{{2}})\s+0x({_HEX}{{8}})")
_DIAG_MESSAGE_TEXT = re.compile(rf"\[(?:CPX|DS401|ETG)\s+0x({_HEX}{{8}})\]")
_MASTER_ABORT = re.compile(rf"SDO\s+(?:upload|download)\s+0x({_HEX}{{4}}):({_HEX}{{2}})\s+"
                           rf"aborted with\s+0x({_HEX}{{8}})")
_TAB_15_DASH = re.compile(rf"(?<={_HEX})\s*-\s*(?={_HEX})")


@dataclass(frozen=True)
class _Display:
    """A display style's three rows (error code, error register, data) and the words of its
    PasteErrors: Sirio (§7.2) and Pegaso (§7.3) read the same way but for the data's order."""

    code: re.Pattern[str]
    register: re.Pattern[str]
    data: re.Pattern[str]
    register_name: str
    data_name: str
    data_alone: str  # the PasteError for a data row without the code and register rows
    high_first: bool = False  # the data row prints byte 4 first


_SIRIO = _Display(
    re.compile(rf"Err\.\s*Code\s+({_HEX}{{1,4}})\b"),
    re.compile(rf"Err\.\s*Reg\.\s+({_HEX}{{1,4}})\b"),
    re.compile(r"0x\s*low\s+([0-9A-Fa-f\s]*?)\s*high"),
    "Err. Reg.", "Sirio data row",
    "Sirio display (seed 000 §7.2): the data row alone has no error code; paste the Err. Code "
    "and Err. Reg. rows too")
_PEGASO = _Display(
    re.compile(rf"ERR\s*CODE\s*\[0x({_HEX}+)\]"),
    re.compile(rf"ERR\s*REG\b[^\[]*\[0x({_HEX}+)\]"),
    re.compile(r"ERR\s*DATA\s*(?:alto\s*)?\[0x([0-9A-Fa-f\s]*)\]"),
    "ERR REG", "Pegaso ERR DATA",
    "Pegaso display (seed 000 §7.3): the ERR DATA row alone has no error code; paste the "
    "ERR CODE and ERR REG rows too", high_first=True)


def canonical(text: str) -> str:
    """``text`` as :func:`app.decoder.decode` reads it; PasteError for a line without code."""
    for parse in (_twincat, _sirio, _pegaso, _aitraceprint, _fieldrig):
        found = parse(text)
        if found is not None:
            return found
    if re.fullmatch(rf"[\s{_HEX[1:-1]}-]+", text) and "-" in text:
        # seed 002 Tab. 15 prints the message with dashes inside ("02 - 37", "00 00-00")
        return _TAB_15_DASH.sub(" ", text)
    return text


def _whole_bytes(digits: str, where: str) -> bytes:
    """Hex bytes as a display prints them ("02 00 0B", "0200000400"); PasteError otherwise."""
    if any(len(group) % 2 for group in digits.split()):
        raise PasteError(f"{where}: the emergency data are whole bytes, two hex digits each")
    return bytes.fromhex(digits)


def _emergency(code: int, register: int, data: bytes) -> str:
    return f"{code:04X} {register:02X} {data.hex(' ').upper()}".strip()


def _twincat(text: str) -> str | None:
    logged = _TWINCAT_EMCY.search(text)
    if logged:
        return logged.group(1).replace("'", " ").rstrip(" .")
    quoted = _AL_QUOTED.search(text) or _AL_WITH_CODE.search(text)
    return quoted.group(1) if quoted else None


def _register(raw: str, where: str) -> int:
    value = int(raw, 16)
    if value > 0xFF:
        raise PasteError(f"{where} {raw}: the error register (0x1001) is one byte")
    return value


def _display(text: str, style: _Display) -> str | None:
    code, reg, data = (p.search(text) for p in (style.code, style.register, style.data))
    if data is None:
        return f"0x{code.group(1)}" if code else None  # the code row alone
    if code is None or reg is None:
        raise PasteError(style.data_alone)
    raw = _whole_bytes(data.group(1), style.data_name)
    return _emergency(int(code.group(1), 16), _register(reg.group(1), style.register_name),
                      raw[::-1] if style.high_first else raw)


def _sirio(text: str) -> str | None:
    return _display(text, _SIRIO)


def _pegaso(text: str) -> str | None:
    return _display(text, _PEGASO)


def _aitraceprint(text: str) -> str | None:
    state = _TRACE_STATE.search(text)
    if state:
        return f"0x{int(state.group(1)):04X}"  # the AL status code, printed in decimal
    code, reg, data = (p.search(text) for p in (_TRACE_CODE, _TRACE_REG, _TRACE_DATA))
    if code and reg and data:
        return _emergency(int(code.group(1), 16), _register(reg.group(1), "emcyReg"),
                          _whole_bytes(data.group(1), f"data=0x{data.group(1)}"))
    if _TRACE_ERROR_CONTROL.search(text):
        raise PasteError("ErrorControl's errorLocCode is the PLC's: seed 000 §7.4 prints it "
                         "without explaining it, and the rig's master does not log it")
    if _TRACE_PLC_ALARM.search(text):
        raise PasteError("'Alarm 77:4' is a PLC alarm of the §7.4 trace (mask 00000100), not a "
                         "device code: the emergency and state lines next to it carry those")
    if _TRACE_CHANGE.search(text):
        raise PasteError("SlaveStateChange carries no code: the AL status code is on the "
                         "EcatManagerSlaveStateCallback line just before it (seed 000 §7.4)")
    return None


def _fieldrig(text: str) -> str | None:
    message = _DIAG_MESSAGE_TEXT.search(text)  # "error [CPX 0xE1000002] CPX error 2: ..."
    if message:
        return f"0x{message.group(1)}"
    emcy = _FIELDRIG_EMCY.search(text)
    if emcy:
        code = int(emcy.group(1), 16) if emcy.group(1) else 0  # "error reset" is 0x0000
        return _emergency(code, int(emcy.group(2), 16),
                          _whole_bytes(emcy.group(3), "emergency data"))
    abort = _FIELDRIG_ABORT.search(text) or _MASTER_ABORT.search(text)
    if abort is None:
        return None
    index, sub, code = (int(g, 16) for g in abort.groups())
    frame = bytes((0x80,)) + index.to_bytes(2, "little") + bytes((sub,)) \
        + code.to_bytes(4, "little")
    return frame.hex(" ")  # the DS 301 abort frame, so that the reading names the object
