"""Bit registers in each device's own words: the error register 0x1001 (byte 2 of a CoE /
CANopen emergency), and a 0x1001 or 0x10F3:5 ("Flags" of the diagnosis history) value as the
Objects tab shows it.

The words are the devices' tables, said by ``devices.bitwords`` as the Slave and Objects
tabs say them; this module picks the table of the device a reading
belongs to and finds the object and its value in what is pasted:

- the CPX-E-EC: seed 002 Tab. 22 (``devices.cpx.codes.ERROR_REGISTER_BITS``);
- the drive (on CANopen and on EtherCAT): seed 004 ch. 4, DS 301's table
  (``devices.canopen.emcy.REGISTER_BIT_NAMES``);
- the FastCAT: seed 000 §7 names one value, "0x81 (device error)"
  (``devices.fastcat.alarms.EMERGENCY_REGISTER_TEXT``), DS 301's words for any other;
- the TRS-CAT: seed 001 names no bits, so DS 301's.

0x10F3:5: the TRS-CAT's in seed 001 §9.3.7's words (bits 1-3, ``devices.trscat.diagnostics.
FLAG_TEXT``), the CPX-E-EC's in seed 002 Tab. 18 / 19's (bits 0 and 4,
``devices.cpx.history.FLAG_TEXT``); the other bits each model keeps are ETG.1020's.

An object query is ``INDEX:SUB`` then the value, as the Objects tab's row reads (``0x1001:0
Error Register U8 ro 131``) or typed (``0x1001:0 = 0x83``): the value in decimal unless it
has ``0x``, as the Objects tab's Value box takes it; without a value every bit is listed.
The tab shows it in hex with its words (``0x83 = Generic Error, ...``): those are skipped.

An SDO upload as the CANopen tab's frame log shows it (``upload 0x1001:00 = 21``) is the
drive's 0x1001, its bytes in hex: the drive is the one device on CAN.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, replace

from app.decoder_meaning import CANOPEN, CPX, FASTCAT, SERVO, TRSCAT, DecodeError, Meaning
from devices.bitwords import BitWords, FlagWords
from devices.canopen import emcy as ds301
from devices.cpx import codes as cpx
from devices.cpx import history as cpx_history
from devices.cpx.objects import TYPE_NAMES as CPX_TYPES
from devices.events import fmt_hex
from devices.fastcat import alarms as fastcat
from devices.od import IEC_NAMES, DataType
from devices.trscat import diagnostics as trscat_diag
from devices.trscat.objects import TYPE_NAMES as TRSCAT_TYPES


@dataclass(frozen=True)
class Sourced:
    """A device's words for a register (``devices.bitwords``) and where they come from."""

    source: str
    words: BitWords
    note: str = ""  # why these words: "seed 001 names no bits"


_DS301 = ds301.REGISTER_WORDS
_DRIVE = Sourced("seed 004 ch. 4", _DS301)
REGISTER_WORDS: dict[str, Sourced] = {
    CPX: Sourced("seed 002 Tab. 22", cpx.ERROR_REGISTER_WORDS),
    SERVO: _DRIVE,
    CANOPEN: _DRIVE,  # the drive's CANopen node's own codes
    TRSCAT: Sourced("DS 301", _DS301, note="seed 001 names no bits"),
    FASTCAT: Sourced("seed 000 §7", replace(_DS301, whole={
        fastcat.EMERGENCY_REGISTER: fastcat.EMERGENCY_REGISTER_TEXT})),
}
_PLAIN = Sourced("DS 301", _DS301)


def register_text(register: int, family: str | None = None) -> str:
    """``0x81: Generic Error, Manufacturer Specific`` (DS 301); with a family, in that
    device's words and naming them: ``0x81 (seed 000 §7): device error``."""
    if family is None:
        return f"{fmt_hex(register, 2)}: {_PLAIN.words.text(register)}"
    sourced = REGISTER_WORDS.get(family, _PLAIN)
    words = sourced.words
    source = "; ".join(filter(None, (sourced.source, sourced.note)))
    if words.whole and register not in words.whole:  # a value the seed does not name
        named = ", ".join(fmt_hex(v, 2) for v in words.whole)
        source = f"DS 301; {sourced.source} names only {named}"
    return f"{fmt_hex(register, 2)} ({source}): {words.text(register, notes=True)}"


# ---- an object and its value, as the Objects tab shows it --------------------------------
@dataclass(frozen=True)
class _Object:
    sub: int
    name: str
    size: int  # bytes: 1 for a U8, 2 for a U16
    read: Callable[[int | None, str], list[Meaning]]  # (value or None, title) -> readings


def _error_register(value: int | None, title: str) -> list[Meaning]:
    """The devices with a 0x1001 (the FastCAT has none): each in its own words."""
    found = []
    for family in (TRSCAT, CPX, SERVO):
        sourced = REGISTER_WORDS[family]
        source = f"{sourced.source} ({sourced.note})" if sourced.note else sourced.source
        words = sourced.words
        text = words.text(value, notes=True) if value is not None else words.listing(True)
        found.append(Meaning(family, title, text + ".", source))
    return found


# 0x10F3:5 of each device that has a diagnosis history, and the source of its words.
_FLAGS: dict[str, tuple[FlagWords, str]] = {
    TRSCAT: (trscat_diag.FLAG_WORDS, "seed 001 §9.3.7 (bit 0: ETG.1020)"),
    CPX: (cpx_history.FLAG_WORDS, "seed 002 Tab. 18, 19 (bits 1-3, 5: ETG.1020)"),
}


def _diag_flags(value: int | None, title: str) -> list[Meaning]:
    return [Meaning(family, title,
                    (words.listing() if value is None else words.text(value)) + ".", source)
            for family, (words, source) in _FLAGS.items()]


_OBJECTS: dict[int, _Object] = {
    0x1001: _Object(0, "Error register", 1, _error_register),
    0x10F3: _Object(5, "Flags", 2, _diag_flags),
}
_ADDRESS = re.compile(r"\s*(?:0x)?([0-9a-f]{4})\s*:\s*(?:0x)?([0-9a-f]{1,2})(?![0-9a-z])(.*)",
                      re.IGNORECASE | re.DOTALL)
_NUMBER = re.compile(r"\(?(0x[0-9a-f]+|\d+)\)?", re.IGNORECASE)
# The Objects tab writes a value's words after it ("0x03 = Generic Error, Current", the
# entry's explain): after "=" behind the number they are the tab's reading, not a value.
_SAID = re.compile(r"\b(0x[0-9a-f]+|\d+)\s*=\s*[a-z].*", re.IGNORECASE | re.DOTALL)
# What else an Objects tab row holds: the access column and every manual's type names.
_ROW_WORDS = {"ro", "rw", "p", "value"} | {
    names.names[dtype].lower() for names in (IEC_NAMES, CPX_TYPES, TRSCAT_TYPES)
    for dtype in (DataType.UNSIGNED8, DataType.UNSIGNED16)}


def object_readings(text: str) -> list[Meaning]:
    """The readings of ``0x1001:0 = 0x83`` and the like; [] when ``text`` is no such object
    query, DecodeError for one the tab cannot read (another sub, two values, too wide)."""
    found = _ADDRESS.fullmatch(text)
    if found is None or int(found.group(1), 16) not in _OBJECTS:
        return []
    index, sub = int(found.group(1), 16), int(found.group(2), 16)
    obj = _OBJECTS[index]
    address = f"{fmt_hex(index, 4)}:{obj.sub}"
    if sub != obj.sub:
        raise DecodeError(f"{fmt_hex(index, 4)}:{sub}: the Codes tab reads {address} "
                          f"({obj.name}), sub {obj.sub}")
    value = _value(found.group(3), obj, address)
    title = f"{address} {obj.name}" + ("" if value is None else
                                       f" = {fmt_hex(value, 2 * obj.size)}")
    return obj.read(value, title)


def _value(rest: str, obj: _Object, address: str) -> int | None:
    values = []
    name_words = set(obj.name.lower().split())
    rest = _SAID.sub(r"\1", rest)
    for token in re.split(r"[\s=,;]+", rest.strip()):
        number = _NUMBER.fullmatch(token)
        if number:
            digits = number.group(1).lower()
            values.append(int(digits, 16) if digits.startswith("0x") else int(digits))
        elif token and token.lower() not in _ROW_WORDS | name_words:
            raise DecodeError(f"{token!r} after {address}: give its value, decimal or 0x.. "
                              f"hex, as the Objects tab shows it ({address} = 0x83)")
    if len(set(values)) > 1:
        raise DecodeError(f"{address}: two values ({', '.join(map(str, values))}); give one")
    if not values:
        return None
    if values[0] >= 1 << 8 * obj.size:
        raise DecodeError(f"{address} is {'one byte' if obj.size == 1 else 'two bytes'}: "
                          f"{fmt_hex(values[0], 2)} does not fit")
    return values[0]


# ---- an SDO upload, as the CANopen tab's frame log shows it --------------------------------
# "node 2 ->: upload 0x1001:00 = 21" (devices/canopen/decode.py), or the tab's Last SDO row
# "Upload (read) 0x1001:00 from node 2: value 21." (app/ui/drive/canopen_panel.py): the
# expedited bytes in hex, byte 0 first, unlike the Objects tab's decimal; without a value the
# master's request.
_UPLOAD = re.compile(r"\bupload(?:\s*\(read\))?\s+0x([0-9a-f]{4}):([0-9a-f]{2})"
                     r"(?:\s+from node \d+)?(?:\s*(?:=|:\s*value)\s*((?:[0-9a-f]{2}\s*)+))?"
                     r"\.?\s*$", re.IGNORECASE)
# The one device on CAN is the drive (seed 004 ch. 4): its words are the node's.
_NODE = SERVO


def upload_readings(text: str) -> list[Meaning]:
    """The frame log's SDO upload of an object the Codes tab reads, as the drive's node's
    value; [] for another line or object, DecodeError for one the node cannot have sent."""
    found = _UPLOAD.search(text)
    if found is None or int(found.group(1), 16) not in _OBJECTS:
        return []
    index, sub = int(found.group(1), 16), int(found.group(2), 16)
    obj = _OBJECTS[index]
    address = f"{fmt_hex(index, 4)}:{obj.sub}"
    if index != 0x1001:  # the drive's node has no diagnosis history (it aborts the upload)
        raise DecodeError(f"the drive's CANopen node has no {fmt_hex(index, 4)}, the one "
                          "device on CAN: it answers an upload with abort 0x06020000")
    if sub != obj.sub:
        raise DecodeError(f"{fmt_hex(index, 4)}:{sub:02X}: the Codes tab reads {address} "
                          f"({obj.name}), sub {obj.sub}")
    title = f"{address} {obj.name}"
    sourced = REGISTER_WORDS[_NODE]
    if found.group(3) is None:
        return [Meaning(_NODE, title + " (SDO upload request, CANopen node)",
                        sourced.words.listing() + ".", sourced.source)]
    data = bytes.fromhex(found.group(3))
    if len(data) != obj.size:
        raise DecodeError(f"{address} is one byte; the upload carries {len(data)} "
                          f"({found.group(3).strip()})")
    value = int.from_bytes(data, "little")
    return [Meaning(_NODE, f"{title} = {fmt_hex(value, 2)} (SDO upload, CANopen node)",
                    sourced.words.text(value) + ".",
                    f"{sourced.source} (the frame log's bytes in hex)")]
