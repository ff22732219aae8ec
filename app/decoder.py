"""Codes in, plain language out: emergencies, AL status codes, EMCY codes, SDO aborts.

A pure function over the devices' own code tables (nothing is copied here): paste what a
logger, a bus monitor or the state panel shows and get every reading the tables allow, each
named with the device family and the seed section it comes from. One number can mean several
things (0x0011 is an AL status code and a CPX-E Text-ID; 0x7500 is an EMCY code of the drive
and of the TRS-CAT): all readings are listed, the family says which device would send it.

Accepted input (case and ``0x`` prefixes do not matter):

- an emergency as the master logs it: ``FF00 81 02 00 00 04 00`` (code, register, data), the
  TwinCAT line ``CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00')`` or the raw 8-byte CAN frame
  ``00 FF 81 02 00 00 04 00`` (code little endian); an 8-byte SDO abort frame ``80 ...``;
- the master's log lines in each of its styles (seed 000 §7.1-§7.4: TwinCAT, Sirio, Pegaso with
  its data high byte first, AITracePrint with the AL status code in decimal), read by
  :mod:`app.decoder_paste`;
- a 0x10F3 diagnosis message as bytes (ETG.1020, seed 002 Tab. 15, 16 bytes or more), a
  32-bit value as its four bytes low first (``02 00 00 E1``: the Diag Code as Tab. 16 prints
  it), a Modbus exception response ``83 02`` (or with the unit id, ``05 83 02``);
- one number: an AL status code (``0x8204``, ``0x0052``), an EMCY / 0x603F code (``8130``), an
  SDO abort code (``0x06020000``), a FastCAT 0x5400 word (``0x04000002``), an ETG.1020 Diag
  Code (``0xE8007500``), the drive's 0x1003:1 (``0x00108611``: alarm 16, code 0x8611), a
  CPX-E Text-ID (``0x3702``), a FastCAT alarm code (``0x04``);
- a name: ``MISSING_NODE_ANSWER``, ``CO_E_TARATURA``, ``coupler:0x04``, ``FOLLOWING_ERROR``,
  or a drive alarm number ``alarm 16`` (the drive's display shows it in decimal). A bare
  number of 1-3 decimal digits (``16``) reads as hex in the code tables and as the drive
  alarm of that decimal number: both are listed.
"""

from __future__ import annotations

import re
import struct
from dataclasses import replace

from app.decoder_events import event_readings
from app.decoder_meaning import (
    CANOPEN,
    CPX,
    DIAG,
    ETHERCAT,
    FASTCAT,
    MODBUS,
    SDO,
    SERVO,
    TRSCAT,
    DecodeError,
    Meaning,
    al_status_registers,
    modbus_exception,
)
from app.decoder_nmt import nmt_readings
from app.decoder_paste import PasteError, canonical
from app.decoder_registers import object_readings, register_text, upload_readings
from app.decoder_states import MASTER, state_readings
from app.modbus.pdu import EXCEPTION_FLAG
from devices.canopen import emcy as ds301
from devices.cpx import codes as cpx
from devices.cpx.messages import CHANNEL_INPUT, CHANNEL_OUTPUT, DiagMessage, parse_emergency
from devices.device import CommandError
from devices.ethercat import AL_STATUS_CODES, MANUFACTURER_AREA, describe_al_status_code
from devices.events import fmt_hex
from devices.fastcat import alarms as fastcat
from devices.od import ABORT_TEXT, AbortCode
from devices.servo import alarms as servo
from devices.trscat.diagnostics import DIAG_CODE_MANUFACTURER, FAULTS

MAX_FASTCAT_MODULE = fastcat.MAX_MODULES  # seed 000 §2: at most 16 modules on a coupler

# The drive's CANopen node's own codes and the 0x1001 bits, in the model's words.
_REGISTER_NAMES = ds301.REGISTER_BIT_NAMES
_CANOPEN_CODES = ds301.EMCY_TEXT
_SERVO_FIELDBUSES = ("modbus", "profinet")  # their tables differ in alarms 30-35
_SERVO_EFFECT = servo.EFFECT_TEXT  # seed 004 ch. 3 "Azione", in the model's words


# ---- entry point -------------------------------------------------------------------------
def decode(text: str) -> list[Meaning]:
    """Every reading of ``text``; DecodeError when it is not something to look up at all."""
    return _decode(text) + al_status_registers(text)


def _decode(text: str) -> list[Meaning]:
    raw = text.strip()
    if not raw:
        raise DecodeError("nothing to decode: paste a code, an emergency or a name")
    states = state_readings(raw)  # before canonical(): "node 2: boot-up" is no FieldRig line
    if states:
        return states
    named = event_readings(raw)  # seed 003's "network recovery", "resync events", ...
    if named:
        return named
    nmt = nmt_readings(raw)  # "NMT 01 02", the CANopen tab's frame log row
    if nmt:
        return nmt
    uploads = upload_readings(raw)  # "upload 0x1001:00 = 21", the CANopen tab's frame log
    if uploads:
        return uploads
    objects = object_readings(raw)  # "0x1001:0 = 0x83", as the Objects tab shows the value
    if objects:
        return objects
    try:
        raw = canonical(raw).strip()
    except PasteError as exc:
        raise DecodeError(str(exc)) from None
    if not raw:  # a log line emptied of its bytes: "(Hex: )"
        raise DecodeError("nothing to decode in that line: it holds no code or bytes")
    exception = re.fullmatch(r"(?:modbus\s*)?exception\s*(?:code\s*)?(?:0x)?([0-9a-f]{1,2})",
                             raw, re.IGNORECASE)
    if exception:
        return [modbus_exception(None, int(exception.group(1), 16))]
    named = re.search(r"\balarm\s+((?:0x)?[0-9A-Fa-f]+)\s+([A-Z][A-Z0-9_]+)\b"
                      r"(?:\s+module\s+(\d+))?", raw)
    if named:  # "alarm 0x0B TARATURA module 2": the Event log's line, a Reported alarm
        module = int(named.group(3)) if named.group(3) else None
        return _alarm_line(named.group(1), named.group(2), module)
    alarm = re.fullmatch(r"(?:drive\s*)?alarm\s*(\d{1,3})", raw, re.IGNORECASE)
    if alarm:
        return _drive_alarm_number(int(alarm.group(1)))
    alarm = re.fullmatch(r"alarm\s*0x([0-9a-f]{1,4})", raw, re.IGNORECASE)
    if alarm:  # the Event log's code without its name: the tables' code, or the drive's alarm
        value = int(alarm.group(1), 16)
        found = [m for m in _number(value, len(alarm.group(1)))
                 if not m.text.startswith("Not in any device table")]
        found += [_drive_alarm(spec) for spec in _drive_specs() if spec.code == value]
        if not found:
            raise DecodeError(f"no table has an alarm {fmt_hex(value, 2)}, and the drive has "
                              f"no alarm {value} (its display counts in decimal)")
        return found
    tokens = [t for t in re.split(r"[\s,;]+", raw) if t]
    if not tokens:  # separators only: ",", "(Hex: ; )"
        raise DecodeError("nothing to decode in that line: it holds no code or bytes")
    numbers = [_hex(t) for t in tokens]
    if any(n is None for n in numbers):
        if len(tokens) == 1 or ":" in raw:
            return _name(raw)
        raise DecodeError(f"{raw!r}: give hex bytes (e.g. FF00 81 02 00 00 04 00), one code or "
                          "one name")
    values = [n for n in numbers if n is not None]
    widths = [len(_digits(t)) for t in tokens]
    if len(values) == 1:
        found = _number(values[0], widths[0])
        # The drive's display shows its alarm in decimal (seed 004 ch. 5): a bare 1-3 digit
        # number ("16") may be that too; it is listed after the hex readings, not instead.
        if re.fullmatch(r"\d{1,3}", raw):
            found += [_drive_alarm(spec) for spec in _drive_specs() if spec.code == int(raw)]
        return found
    return _frame(values, widths)


def _digits(token: str) -> str:
    t = token.lower()
    t = t[2:] if t.startswith("0x") else t
    return t[:-1] if t.endswith("h") else t


def _hex(token: str) -> int | None:
    digits = _digits(token)
    if not digits or not re.fullmatch(r"[0-9a-f]+", digits):
        return None
    return int(digits, 16)


# ---- frames ------------------------------------------------------------------------------
def _frame(values: list[int], widths: list[int]) -> list[Meaning]:
    as_bytes = all(w <= 2 for w in widths)
    if as_bytes and len(values) in (2, 3) and values[-2] > EXCEPTION_FLAG and values[-1]:
        # seed 004 ch. 2 "Eccezioni": function code + 0x80, exception code (unit id first)
        return [modbus_exception(values[-2] & ~EXCEPTION_FLAG, values[-1])]
    if as_bytes and len(values) == 4:  # a 32-bit value as its bytes on the wire, low first
        return _number(int.from_bytes(bytes(values), "little"), 8)
    if as_bytes and len(values) >= DIAG_HEADER_BYTES:
        return _diag_message(bytes(values))
    if len(values) == 8 and as_bytes:
        frame = bytes(values)
        if frame[0] == 0x80:  # DS 301 "abort transfer" command specifier
            index = int.from_bytes(frame[1:3], "little")
            code = int.from_bytes(frame[4:8], "little")
            where = f"object {fmt_hex(index, 4)}:{frame[3]:02X}"
            return [replace(m, title=f"{m.title} on {where}") for m in _abort(code)] or [
                Meaning(SDO, f"SDO abort frame on {where}",
                        f"abort code {fmt_hex(code, 8)} is not in DS 301", "DS 301")]
        return emergency(int.from_bytes(frame[:2], "little"), frame[2], frame[3:])
    # The register may come in four digits, as the Sirio display prints it (0081, §7.2).
    if widths[0] >= 3 and len(widths) >= 2 and widths[1] <= 4 \
            and all(w <= 2 for w in widths[2:]) and all(v <= 0xFF for v in values[1:]) \
            and values[0] <= 0xFFFF:
        if len(values) > 7:
            raise DecodeError(f"{len(values) - 2} data bytes: an emergency has five data bytes "
                              "after its code and register (FF00 81 02 00 00 04 00)")
        return emergency(values[0], values[1], bytes(values[2:]))
    raise DecodeError("bytes not understood: an emergency is 'CODE REG B0 B1 B2 B3 B4' "
                      "(e.g. FF00 81 02 00 00 04 00) or the 8 bytes of a CAN frame; a 0x10F3 "
                      "message 16 bytes or more, a Modbus exception '83 02'")


DIAG_HEADER_BYTES = struct.calcsize("<IHHQ")  # ETG.1020: Diag Code, flags, Text-ID, time stamp


def _diag_message(raw: bytes) -> list[Meaning]:
    """A 0x10F3 message (seed 002 Tab. 15/16, seed 001 §9.3.7): its header, then what its Diag
    Code means in the device tables."""
    try:
        message = DiagMessage.decode(raw)
    except (struct.error, ValueError, KeyError):
        raise DecodeError(f"{len(raw)} bytes but no 0x10F3 diagnosis message: Diag Code (4), "
                          "flags (2), Text-ID (2), time stamp (8), then per parameter its "
                          "flags (2) and value (seed 002 Tab. 15/16)") from None
    marker = message.diag_code >> 24
    values = [value for _dtype, value in message.params]
    if marker == cpx.DIAG_CODE_CPX and len(values) == 2:
        module, channel = values
        side = {CHANNEL_OUTPUT: "output", CHANNEL_INPUT: "input"}.get(channel & 0xC0)
        where = f" on output {channel & 0x3F}" if side == "output" else (
            f" on input {channel & 0x3F}" if side == "input" else "")
        params = f"CPX module {module}, channel {fmt_hex(channel, 2)}{where}"
        family = CPX
    else:
        params = ", ".join(fmt_hex(v, 2) for v in values) or "none"
        family = TRSCAT if marker == DIAG_CODE_MANUFACTURER >> 24 else DIAG
    head = Meaning(family, f"0x10F3 diagnosis message, Diag Code {fmt_hex(message.diag_code, 8)}",
                   f"Type {int(message.dtype)} ({message.dtype.name.lower()} message), Text-ID "
                   f"{fmt_hex(message.text_id, 4)}, time stamp {message.timestamp_ns} ns "
                   f"({message.timestamp_ns / 1e9:.3f} s); parameters: {params}.",
                   "ETG.1020, seed 002 Tab. 15/16")
    return [head, *_diag_code(message.diag_code), *_cpx_text_id(message.text_id)]


def _sentence(text: str) -> str:
    return text if text.endswith((".", "!", "?")) else text + "."


def emergency(code: int, register: int, data: bytes) -> list[Meaning]:
    """An emergency: error code, error register (0x1001), manufacturer bytes."""
    found: list[Meaning] = []
    if code == fastcat.EMERGENCY_CODE and len(data) >= 4:
        found.extend(_fastcat_emergency(register, data))
    found.extend(_servo_emcy(code, data[:1]))
    found.extend(_trscat_emcy(code, data[:1], register))
    found.extend(_cpx_emcy(code, register, data))
    found.extend(_canopen_emcy(code))
    if not found:
        found.append(_emcy_class(code))
    # Each reading's register in its own device's words (seed 002 Tab. 22 for the CPX-E-EC).
    return [replace(m, text=f"{m.text} Error register {register_text(register, m.family)}.")
            for m in found]


def _fastcat_emergency(register: int, data: bytes) -> list[Meaning]:
    """Seed 000 §7: byte 0 module, byte 2 module code (§7.6), byte 3 coupler code (§7.5)."""
    module, module_code, coupler_code = data[0], data[2], data[3]
    title = f"FastCAT emergency {fmt_hex(fastcat.EMERGENCY_CODE, 4)} (device specific)"
    if coupler_code and coupler_code in fastcat.COUPLER_CODES:
        return [_fastcat_alarm(fastcat.COUPLER_CODES[coupler_code], module, title)]
    if module_code and module_code in fastcat.MODULE_CODES:
        return [_fastcat_alarm(fastcat.MODULE_CODES[module_code], module, title)]
    if not module_code and not coupler_code:
        return [Meaning(FASTCAT, title, "No alarm code in the data bytes.", "seed 000 §7")]
    return [Meaning(FASTCAT, title, f"Coupler code (byte 3) {fmt_hex(coupler_code, 2)} / "
                    f"module code (byte 2) {fmt_hex(module_code, 2)} on module {module}: not "
                    "in the seed's tables (§7.5, §7.6).", "seed 000 §7")]


def _fastcat_alarm(row: fastcat.AlarmCode, module: int | None, title: str) -> Meaning:
    """``module``: byte 0 of the emergency data (0 = the coupler); None when not known."""
    where = "" if module is None else (f" on module {module}" if module
                                       else " on the coupler itself (module 0)")
    reset = ("cleared by Reset fault (0x5200:1) or a resync of the EtherCAT line once the "
             "cause is gone" if row.resettable
             else "not resettable: the coupler needs a resync")
    section = "§7.5" if row.table == fastcat.COUPLER else "§7.6"
    return Meaning(FASTCAT, title,
                   f"{row.table.capitalize()} alarm {fmt_hex(row.code, 2)} {row.symbol}{where}: "
                   f"{row.description}. It is {reset}.", f"seed 000 §7, {section}")


def _servo_emcy(code: int, vendor: bytes) -> list[Meaning]:
    """Seed 004 ch. 5: each drive alarm sends its 0x603F code, the alarm number in byte 0."""
    specs = [s for s in _drive_specs(servo.CODED_FIELDBUSES) if s.error_code_or_generic == code]
    if vendor and any(s.code == vendor[0] for s in specs):
        specs = [s for s in specs if s.code == vendor[0]]
    return [Meaning(SERVO, f"Drive error code {fmt_hex(code, 4)} (0x603F)",
                    f"Alarm {s.code} {s.name}: {s.description}; {_SERVO_EFFECT[s.effect]}"
                    f"{_reset_note(s)}.", "seed 004 ch. 3, ch. 5")
            for s in specs]


def _trscat_emcy(code: int, vendor: bytes, register: int | None = None) -> list[Meaning]:
    """``register``: the emergency's 0x1001 byte, which tells 0x7100's two causes apart
    (overcurrent sets the current bit, undervoltage the voltage bit); None for a bare code.
    The byte holds every active error's bits (DS301), so a cause fits when its bits are all
    in it; with both bits set (another error active) both causes are listed."""
    slot = f" (slot {vendor[0]})" if vendor and vendor[0] else ""
    faults = [f for f in FAULTS.values() if f.code == code]
    if register is not None:
        faults = [f for f in faults if register & f.register == f.register] or faults
    out = []
    for fault in faults:
        effect = []
        if fault.bus_shutdown:
            effect.append("the TRS bus shuts down until the logic supply is switched off")
        if fault.deadlock:
            effect.append("the ESM falls back to PRE-OP and stays there")
        tail = f"; {'; '.join(effect)}" if effect else ""
        out.append(Meaning(TRSCAT, f"TRS-CAT application error {fmt_hex(code, 4)}",
                           f"{fault.text}{slot}{tail}.", "seed 001 §9.3.7"))
    return out


def _cpx_emcy(code: int, register: int, data: bytes) -> list[Meaning]:
    """Seed 002 Tab. 20-26: status bits, module, CPX error number (bytes 3-5) and byte 7."""
    if code not in cpx.EMCY_CODES:
        return []
    text = _sentence(cpx.EMCY_CODES[code])
    if len(data) == 5 and code != cpx.EMCY_NO_ERROR:
        fields = parse_emergency(code.to_bytes(2, "little") + bytes((register,)) + data)
        bits = [cpx.STATUS_BITS[b] for b in range(8) if fields["status_bits"] >> b & 1]
        error = cpx.CPX_ERRORS.get(fields["cpx_error"])
        what = error.text if error else f"CPX error number {fields['cpx_error']}"
        # Tab. 26 makes byte 7 no more precise than "e.g. the first faulty channel", and
        # 0 is also what an error without a channel carries: the value, not a channel claim
        text += (f" Module {fields['module']}, {what}"
                 f"{'; status: ' + ', '.join(bits) if bits else ''}; byte 7 = {fields['info']}"
                 " (additional information, e.g. the first faulty channel).")
    return [Meaning(CPX, f"CPX-E emergency code {fmt_hex(code, 4)}", text,
                    "seed 002 §2.5.3 Tab. 20-26")]


def _canopen_emcy(code: int) -> list[Meaning]:
    if code not in _CANOPEN_CODES:
        return []
    return [Meaning(CANOPEN, f"EMCY code {fmt_hex(code, 4)}", _sentence(_CANOPEN_CODES[code]),
                    "DS 301, seed 004 ch. 4")]


def _emcy_class(code: int) -> Meaning:
    """No table has the code: say at least which DS 301 class it belongs to (its high byte)
    and which 0x1001 bits the drive's CANopen node would set with it."""
    name = ds301.error_class(code) or "not in the DS 301 table"
    bits = [n for bit, n in _REGISTER_NAMES.items() if ds301.register_bits(code) & bit]
    return Meaning(CANOPEN, f"EMCY code {fmt_hex(code, 4)}",
                   f"Not in any device table here; DS 301 class '{name}' (the high byte); "
                   f"error register bits with it: {', '.join(bits) or 'none'}.",
                   "DS 301, seed 004 ch. 4")


# ---- single numbers ----------------------------------------------------------------------
def _number(value: int, digits: int) -> list[Meaning]:
    found: list[Meaning] = []
    if value > 0xFFFF or digits > 4:
        found.extend(_abort(value))
        found.extend(_fastcat_word(value))
        found.extend(_diag_code(value))
        found.extend(_error_field(value))
        if not found:
            raise DecodeError(f"{fmt_hex(value, 8)} is in none of the tables (SDO abort codes, "
                              "0x5400, ETG.1020 Diag Codes, the drive's 0x1003)")
        return found
    found.extend(al_status(value))
    found.extend(_servo_emcy(value, b""))
    found.extend(_trscat_emcy(value, b""))
    found.extend(_cpx_emcy(value, 0, b""))
    found.extend(_canopen_emcy(value))
    found.extend(_cpx_text_id(value))
    if digits <= 2:
        found.extend(_fastcat_code(value))
    if not found:
        found.append(_emcy_class(value))
    return found


def al_status(code: int) -> list[Meaning]:
    """Seed 000 §7.7: the ETG codes, and the FastCAT's 0x80XX (module in byte 1, coupler code
    in byte 0; a module alarm has none), read by the FastCAT's decoder, as the State and Line
    tabs read it (``devices.fastcat.alarms.decode_al_status``)."""
    if code in AL_STATUS_CODES:
        return [Meaning(ETHERCAT, f"AL status code {fmt_hex(code, 4)}",
                        _sentence(AL_STATUS_CODES[code]), "seed 000 §7.7")]
    found = fastcat.decode_al_status(code)
    if found is None and code == MANUFACTURER_AREA:
        return [Meaning(ETHERCAT, f"AL status code {fmt_hex(code, 4)}",
                        f"{describe_al_status_code(code)}: the manufacturer area starts here; a "
                        "FastCAT writes 0x8000 + module number x 0x100 + coupler code.",
                        "seed 000 §7.7")]
    if found is None:
        return []
    title = f"AL status code {fmt_hex(code, 4)} (manufacturer area)"
    where = f"module {found.module}" if found.module else "the coupler itself (module 0)"
    row = found.coupler
    return [Meaning(FASTCAT, title, f"FastCAT: {where}, coupler code "
                    f"{fmt_hex(row.code, 2)} {row.symbol}: {row.description}.",
                    "seed 000 §7.5, §7.7")]


def _abort(code: int) -> list[Meaning]:
    try:
        abort = AbortCode(code)
    except ValueError:
        return []
    return [Meaning(SDO, f"SDO abort code {fmt_hex(code, 8)}", _sentence(ABORT_TEXT[abort]),
                    "DS 301, seed 004 ch. 4")]


def _fastcat_word(word: int) -> list[Meaning]:
    """0x5400 (seed 000 §6.23): emergency data bytes 0..3 as a little-endian UDINT."""
    if word > 0xFFFF_FFFF:
        return []
    data = word.to_bytes(4, "little")
    module, spare, module_code, coupler_code = data
    if spare or bool(module_code) == bool(coupler_code) or module > MAX_FASTCAT_MODULE:
        return []
    row = (fastcat.COUPLER_CODES.get(coupler_code) if coupler_code
           else fastcat.MODULE_CODES.get(module_code))
    if row is None:
        return []
    found = _fastcat_alarm(row, module, f"FastCAT 0x5400 = {fmt_hex(word, 8)}")
    return [replace(found, source="seed 000 §6.23, " + found.source)]


def _error_field(value: int) -> list[Meaning]:
    """The drive's 0x1003:1: its alarm number in bits 16-31, that alarm's 0x603F code in 0-15
    (docs/canopen.md); a word whose code is not its alarm's is no entry the drive writes."""
    if value > 0xFFFF_FFFF:
        return []
    code, number = ds301.ErrorHistory.fields(value)
    return [Meaning(SERVO, f"Drive 0x1003:1 (pre-defined error field) = {fmt_hex(value, 8)}",
                    servo.error_field_text(value, {s.code: s}) + ".", "seed 004 ch. 4, ch. 5")
            for s in _drive_specs(servo.CODED_FIELDBUSES)
            if s.code == number and s.error_code_or_generic == code]


def _diag_code(value: int) -> list[Meaning]:
    """ETG.1020 Diag Codes of 0x10F3 messages: the top byte says what the low bytes hold."""
    marker, low = value >> 24, value & 0xFFFF
    title = f"Diag Code {fmt_hex(value, 8)}"
    if value >> 16 != marker << 8:  # bits 16..23 are zero in every code the devices write
        return []
    if marker == cpx.DIAG_CODE_DS401:
        inner = [*_servo_emcy(low, b""), *_trscat_emcy(low, b""), *_cpx_emcy(low, 0, b""),
                 *_canopen_emcy(low)] or [_emcy_class(low)]
        return [replace(m, title=f"{title}: emergency code {fmt_hex(low, 4)}",
                        source="ETG.1020, " + m.source) for m in inner]
    if marker == cpx.DIAG_CODE_CPX:
        error = cpx.CPX_ERRORS.get(low)
        text = error.text if error else ("no error" if low == 0 else "not in the tables")
        return [Meaning(CPX, f"{title}: CPX error number {low}", text + ".",
                        "seed 002 §2.5.2 Tab. 16")]
    if value >> 24 == DIAG_CODE_MANUFACTURER >> 24:
        return [replace(m, family=TRSCAT, title=f"{title}: manufacturer specific")
                for m in al_status(low)]
    return []


def _cpx_text_id(value: int) -> list[Meaning]:
    if cpx.CPX_TEXT_ID_BASE <= value <= cpx.CPX_TEXT_ID_BASE + 0xFF:
        number = value - cpx.CPX_TEXT_ID_BASE
        error = cpx.CPX_ERRORS.get(number)
        text = error.text if error else ("no error (the fault has gone)" if number == 0
                                         else "not in the tables")
        return [Meaning(CPX, f"CPX-E Text-ID {fmt_hex(value, 4)}: CPX error number {number}",
                        text + ".", "seed 002 §2.5.2 Tab. 17")]
    if value in cpx.TEXT_IDS:
        return [Meaning(CPX, f"CPX-E Text-ID {fmt_hex(value, 4)}",
                        _sentence(cpx.TEXT_IDS[value][1]), "seed 002 §2.5.2 Tab. 17")]
    return []


def _fastcat_code(code: int) -> list[Meaning]:
    """A bare FastCAT code: the coupler table and the module table both number from 0x01."""
    return [_fastcat_alarm(table[code], None, f"FastCAT {table[code].label}")
            for table in (fastcat.COUPLER_CODES, fastcat.MODULE_CODES) if code in table]


# ---- names -------------------------------------------------------------------------------
def _drive_specs(buses: tuple[str, ...] = _SERVO_FIELDBUSES) -> list[servo.AlarmSpec]:
    """Every drive alarm of these fieldbuses' tables, once (alarms 30-35 differ by fieldbus);
    by default of every table."""
    found: dict[tuple[int, str], servo.AlarmSpec] = {}
    for bus in buses:
        for spec in servo.alarm_table(bus).values():
            found.setdefault((spec.code, spec.name), spec)
    return list(found.values())


def _drive_alarm(spec: servo.AlarmSpec) -> Meaning:
    coded = any(servo.alarm_table(bus).get(spec.code) == spec for bus in servo.CODED_FIELDBUSES)
    code = (f"0x603F code {fmt_hex(spec.error_code_or_generic, 4)}" if coded else
            "no 0x603F code (a Profinet drive has no 0x603F and sends no emergency, ch. 6)")
    return Meaning(SERVO, f"Drive alarm {spec.code} {spec.name}",
                   f"{_first_capital(spec.description)}; {_SERVO_EFFECT[spec.effect]}; "
                   f"{code}{_reset_note(spec)}.", "seed 004 ch. 3, ch. 5")


def _first_capital(text: str) -> str:
    """str.capitalize() lowercases the rest: the seed's IGBT, DSP, LS1 and PDO would not
    survive it."""
    return text[:1].upper() + text[1:]


_BUS_NAMES = {"modbus": "Modbus", "canopen": "CANopen", "ethercat": "EtherCAT",
              "profinet": "Profinet"}


def _reset_note(spec: servo.AlarmSpec) -> str:
    """How each fieldbus resets the alarm (seed 004 ch. 2 R00 bit 3, ch. 4 / ch. 5 0x80 on
    0x6040, ch. 6 Control Word 0x08 and "Resettabile" NO), from the drive's tables."""
    by_hint: dict[str, list[str]] = {}
    never: list[str] = []
    for bus, label in _BUS_NAMES.items():
        row = servo.alarm_table(bus).get(spec.code)
        if row is None or row.name != spec.name:
            continue
        if row.resettable:
            by_hint.setdefault(servo.RESET_HINT[bus], []).append(label)
        else:
            never.append(label)
    parts = []
    if by_hint:
        ways = " or ".join(f"{hint} on {', '.join(buses)}" for hint, buses in by_hint.items())
        parts.append(f"reset, once the cause is gone, with {ways}")
    if never:
        # 0x6040 cannot reach a slave in INIT (docs/ethercat-coe.md "Resetting 35")
        why = " (the slave stays in INIT)" if never == ["EtherCAT"] else ""
        parts.append(f"not resettable on {', '.join(never)}: only a power cycle clears it"
                     f"{why}")
    return "; " + "; ".join(parts)


def _drive_alarm_number(number: int) -> list[Meaning]:
    found = [_drive_alarm(s) for s in _drive_specs() if s.code == number]
    if not found:
        raise DecodeError(f"the drive has no alarm {number} (seed 004 ch. 3, ch. 5)")
    return found


def _alarm_line(code: str, name: str, module: int | None = None) -> list[Meaning]:
    """An alarm event's code and name: the name finds the rows, the code (as the device's
    family writes it: "5", "0x04", "0xA000", "0x3708") keeps its own device's. UNDERVOLTAGE is
    drive alarm 5 and CPX error 8 (Text-ID 0x3708). ``module``: the event's module (slot)."""
    found = _name(name, module)
    mine = re.compile(rf"(?<!\w){re.escape(code)}(?!\w)", re.IGNORECASE)
    return [m for m in found if mine.search(m.title)] or found


def _name(text: str, module: int | None = None) -> list[Meaning]:
    found: list[Meaning] = []
    try:
        row = fastcat.parse_fault(text)
    except CommandError:
        row = None
    if row is not None:
        found.append(_fastcat_alarm(row, module, f"FastCAT {row.label}"))
    wanted = text.strip().upper()
    found.extend(_drive_alarm(s) for s in _drive_specs() if s.name == wanted)
    fault = FAULTS.get(wanted)
    if fault is not None:
        found.extend(m for m in _trscat_emcy(fault.code, b"") if m.text.startswith(fault.text))
    for error in cpx.CPX_ERRORS.values():
        if error.symbol == wanted:
            found.extend(_cpx_text_id(error.text_id))
    if not found:
        raise DecodeError(f"{text!r} is no code and no alarm name the tables know")
    return found


__all__ = [
    "CANOPEN",
    "CPX",
    "DIAG",
    "ETHERCAT",
    "FASTCAT",
    "MASTER",
    "MODBUS",
    "SDO",
    "SERVO",
    "TRSCAT",
    "DecodeError",
    "Meaning",
    "al_status",
    "decode",
    "emergency",
    "register_text",
]
