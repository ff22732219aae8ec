"""The SDO oracle of the CAN fuzz: the answer each request is owed, by CiA 301 and the EDS.

Worked out from the request, the node's object dictionary (the EDS: type, access, value range)
and the transfer under way, which the oracle follows itself:

- initiate upload: the object's value, expedited up to 4 bytes, else the segmented start with
  the size; 0x06020000 / 0x06090011 for a missing object / sub-index, 0x06010001 write-only;
- initiate download: a missing object or sub, 0x06010002 read-only first; an expedited value
  then by the drive's length rule (docs/canopen.md §SDO: without the size bit four bytes, of
  which the object takes its width; with it, more bytes than the width -> 0x06070012) and the
  type's and the EDS's value range (0x06090032 too low, 0x06090031 too high). A value that
  passes must be confirmed with 0x60 and then be in the dictionary, unless the object's own
  application check refuses it with a code that object can give (:data:`SETTER_CODES`);
- segments: 0x05040001 outside a transfer of their direction, 0x05030000 on a toggle error,
  else the next upload segment or the download confirmation (the last one writes the value,
  judged as above);
- block upload (no block transfer in the drive): the plain upload above when the initiate
  request's protocol switch threshold (pst, byte 5) is not 0 and the value is at most pst
  bytes (DS 301), else 0x05040001, also for a block upload's later requests;
- block download and command specifier 7: 0x05040001; a client's abort ends the transfer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from devices.canopen.node import CanOpenNode
from devices.od import AbortCode, DataType, OdEntry, SdoAbort, encode

ABORT = 0x80
NO_DATA = 0x0800_0024  # the library's "no data available" (an empty value)
CCS_DOWNLOAD_SEGMENT, CCS_DOWNLOAD, CCS_UPLOAD, CCS_UPLOAD_SEGMENT = 0x00, 0x20, 0x40, 0x60
CCS_ABORT, CCS_BLOCK_UPLOAD, CCS_BLOCK_DOWNLOAD, CCS_INVALID = 0x80, 0xA0, 0xC0, 0xE0
EXPEDITED, SIZE_GIVEN, TOGGLE, LAST = 0x02, 0x01, 0x10, 0x01
BLOCK_SUBCOMMAND = 0x03  # a block upload request's cs: 0 initiate, 1 end, 2 ack, 3 start
WIDTH = {DataType.BOOLEAN: 1, DataType.INTEGER8: 1, DataType.UNSIGNED8: 1,
         DataType.INTEGER16: 2, DataType.UNSIGNED16: 2, DataType.INTEGER32: 4,
         DataType.UNSIGNED32: 4}
SIGNED = {DataType.INTEGER8: 8, DataType.INTEGER16: 16, DataType.INTEGER32: 32}
TYPE_RANGE = {DataType.BOOLEAN: (0, 1), DataType.UNSIGNED8: (0, 0xFF),
              DataType.UNSIGNED16: (0, 0xFFFF), DataType.UNSIGNED32: (0, 0xFFFF_FFFF),
              DataType.INTEGER8: (-0x80, 0x7F), DataType.INTEGER16: (-0x8000, 0x7FFF),
              DataType.INTEGER32: (-0x8000_0000, 0x7FFF_FFFF)}
# An object whose application check may still refuse a value in its EDS range, and how. Every
# object with an application hook may refuse a value (0x06090030) or be refused while the drive
# does not answer (0x08000022); only 0x1010 has its own "cannot store" (no "save" signature),
# only the indirect-access objects name another object that may be read-only, only the PDO
# parameters have the PDO codes. 0x08000000 (general error) is never right for a download.
HOOK_CODES = {int(AbortCode.VALUE_RANGE), int(AbortCode.CANNOT_STORE_STATE)}
INDIRECT = frozenset({0x2000, 0x2005, 0x2006})  # seed 004 ch. 4 parameter / variable access
PDO_CODES = {int(AbortCode.VALUE_TOO_HIGH), int(AbortCode.NOT_MAPPABLE),
             int(AbortCode.PDO_TOO_LONG), int(AbortCode.UNSUPPORTED_ACCESS)}


def setter_codes(index: int) -> set[int]:
    codes = set(HOOK_CODES)
    if index == 0x1010:
        codes.add(int(AbortCode.CANNOT_STORE))
    if index in INDIRECT:
        codes.add(int(AbortCode.READ_ONLY))
    if 0x1400 <= index <= 0x1BFF:
        codes |= PDO_CODES
    return codes


@dataclass
class Transfer:
    direction: str  # "up" or "down"
    index: int
    sub: int
    toggle: int = 0
    data: bytes = b""  # up: what is left to send; down: what came so far


def _value(entry: OdEntry, data: bytes, size_given: bool) -> tuple[Any, int | None]:
    """The value a download carries, or the abort its length or range earns."""
    if entry.dtype is DataType.VISIBLE_STRING:
        return data.decode("latin-1"), None
    if entry.dtype is DataType.OCTET_STRING:
        return data, None
    width = WIDTH[entry.dtype]
    data = data if size_given else data[:width]
    if len(data) > width:
        return None, int(AbortCode.LENGTH_TOO_HIGH)
    if not data:
        return None, int(AbortCode.LENGTH_TOO_LOW)
    value = int.from_bytes(data, "little", signed=entry.dtype in SIGNED)
    low, high = TYPE_RANGE[entry.dtype]
    low = low if entry.low is None else max(low, entry.low)
    high = high if entry.high is None else min(high, entry.high)
    if value < low:
        return None, int(AbortCode.VALUE_TOO_LOW)
    if value > high:
        return None, int(AbortCode.VALUE_TOO_HIGH)
    return value, None


class SdoOracle:
    """Judges one node's SDO answers, request by request, following the transfer itself."""

    def __init__(self) -> None:
        self.transfer: Transfer | None = None
        self.confirmed = 0  # downloads confirmed with their value found in the dictionary

    def reset(self) -> None:
        self.transfer = None  # a node reset / a fresh node

    def judge(self, node: CanOpenNode, request: bytes, answer: bytes | None) -> str | None:
        """Why ``answer`` (None: no answer) is wrong; ``node`` is read right after it."""
        if len(request) != 8:  # "Un messaggio SDO è sempre otto byte": no request at all
            return None if answer is None else "a frame of another length was answered"
        ccs = request[0] & 0xE0
        if ccs == CCS_ABORT:
            self.transfer = None
            return None if answer is None else "a client's abort was answered"
        if answer is None or len(answer) != 8:
            return f"answer {answer!r} to an SDO request"
        transfer, self.transfer = self.transfer, None  # kept only where the protocol goes on
        aborted = answer[0] == ABORT
        code = int.from_bytes(answer[4:8], "little")
        if ccs in (CCS_UPLOAD, CCS_BLOCK_UPLOAD, CCS_DOWNLOAD):
            if answer[1:4] != request[1:4]:
                return "the answer names another object"
            if ccs == CCS_BLOCK_UPLOAD and request[0] & BLOCK_SUBCOMMAND:
                return _abort_is(answer, AbortCode.INVALID_COMMAND, "a block upload's "
                                 "later request with no block upload under way")
            index, sub = int.from_bytes(request[1:3], "little"), request[3]
            must = _access_abort(node, index, sub, ccs == CCS_DOWNLOAD)
            if must is not None:
                return None if aborted and code == must else f"expected abort 0x{must:08X}"
            if ccs == CCS_DOWNLOAD:
                return self._initiate_download(node, request, answer, index, sub)
            if ccs == CCS_BLOCK_UPLOAD and not _may_switch(node, index, sub, request[5]):
                return _abort_is(answer, AbortCode.INVALID_COMMAND,
                                 "a block upload its pst does not let switch")
            return self._initiate_upload(node, answer, index, sub)
        if ccs in (CCS_BLOCK_DOWNLOAD, CCS_INVALID):
            if answer[1:4] != request[1:4]:  # the abort names the request's object (ch. 4)
                return "the abort names another object"
            return _abort_is(answer, AbortCode.INVALID_COMMAND, "a block download / ccs 7")
        direction = "up" if ccs == CCS_UPLOAD_SEGMENT else "down"
        if transfer is None or transfer.direction != direction:
            return _abort_is(answer, AbortCode.INVALID_COMMAND, "a segment outside a transfer")
        if request[0] & TOGGLE != transfer.toggle:
            return _abort_is(answer, AbortCode.TOGGLE_NOT_ALTERNATED, "a toggle error")
        if direction == "up":
            return self._upload_segment(transfer, answer)
        return self._download_segment(node, transfer, request, answer)

    # ---- uploads ---------------------------------------------------------------------------
    def _initiate_upload(self, node: CanOpenNode, answer: bytes, index: int, sub: int
                         ) -> str | None:
        entry = node.dictionary.entry(index, sub)
        try:
            data = encode(entry.dtype, node.dictionary.read(index, sub))
        except SdoAbort as exc:  # the value cannot be read now: that abort, and only that
            return _abort_is(answer, exc.code, "a value that cannot be read now")
        if not data:
            return _abort_is(answer, NO_DATA, "an empty value")
        if len(data) <= 4:
            want = bytes((0x43 | (4 - len(data)) << 2,)) + answer[1:4] + data.ljust(4, b"\0")
            return None if answer == want else f"upload, expected {want.hex(' ')}"
        want = bytes((0x41,)) + answer[1:4] + len(data).to_bytes(4, "little")
        if answer != want:
            return f"segmented upload start, expected {want.hex(' ')}"
        self.transfer = Transfer("up", index, sub, 0, data)
        return None

    def _upload_segment(self, transfer: Transfer, answer: bytes) -> str | None:
        part, rest = transfer.data[:7], transfer.data[7:]
        command = transfer.toggle | (7 - len(part)) << 1 | (0 if rest else LAST)
        want = bytes((command,)) + part.ljust(7, b"\0")
        if answer != want:
            return f"upload segment, expected {want.hex(' ')}"
        if rest:
            self.transfer = Transfer("up", transfer.index, transfer.sub, transfer.toggle ^ TOGGLE,
                                     rest)
        return None

    # ---- downloads -------------------------------------------------------------------------
    def _initiate_download(self, node: CanOpenNode, request: bytes, answer: bytes, index: int,
                           sub: int) -> str | None:
        command = request[0]
        if not command & EXPEDITED:
            if answer[0] != 0x60:
                return "a segmented download to a writable object not confirmed with 0x60"
            self.transfer = Transfer("down", index, sub)
            return None
        size = 4 - (command >> 2 & 3) if command & SIZE_GIVEN else 4
        return self._stored(node, index, sub, request[4:4 + size], bool(command & SIZE_GIVEN),
                            answer, 0x60)

    def _download_segment(self, node: CanOpenNode, transfer: Transfer, request: bytes,
                          answer: bytes) -> str | None:
        data = transfer.data + request[1:8 - (request[0] >> 1 & 7)]
        if not request[0] & LAST:
            if answer[0] != 0x20 | transfer.toggle:
                return f"download segment answered {answer.hex(' ')}"
            self.transfer = Transfer("down", transfer.index, transfer.sub,
                                     transfer.toggle ^ TOGGLE, data)
            return None
        return self._stored(node, transfer.index, transfer.sub, data, True, answer,
                            0x20 | transfer.toggle)

    def _stored(self, node: CanOpenNode, index: int, sub: int, data: bytes, size_given: bool,
                answer: bytes, confirmation: int) -> str | None:
        """A download that carries its value: the length / range abort, or the confirmation
        and the value in the dictionary, or a refusal that object's application may give."""
        entry = node.dictionary.entry(index, sub)
        value, must = _value(entry, data, size_given)
        if must is not None:
            return _abort_is(answer, must, "a value of the wrong length or out of range")
        code = int.from_bytes(answer[4:8], "little")
        if answer[0] == ABORT:
            if entry.setter is not None and code in setter_codes(index):
                return None
            return f"a value in range aborted with 0x{code:08X}"
        if answer[0] != confirmation:
            return f"download answered {answer.hex(' ')}, expected 0x{confirmation:02X}"
        return self._landed(node, entry, value)

    def _landed(self, node: CanOpenNode, entry: OdEntry, value: Any) -> str | None:
        if entry.access.readable:  # read back at once (a live value is read through its getter)
            held = node.dictionary.peek(entry.index, entry.sub)
            if held != value:
                return f"0x{entry.index:04X}:{entry.sub} holds {held!r} after writing {value!r}"
        self.confirmed += 1
        return None


def _access_abort(node: CanOpenNode, index: int, sub: int, write: bool) -> int | None:
    if (index, sub) not in node.dictionary:
        return int(AbortCode.NO_OBJECT if index not in node.dictionary.indices()
                   else AbortCode.NO_SUBINDEX)
    entry = node.dictionary.entry(index, sub)
    if write and not entry.access.writable:
        return int(AbortCode.READ_ONLY)
    if not write and not entry.access.readable:
        return int(AbortCode.WRITE_ONLY)
    return None


def _may_switch(node: CanOpenNode, index: int, sub: int, pst: int) -> bool:
    """DS 301: a server without block upload may answer with the plain protocol when pst is
    not 0 and the value is at most pst bytes (a value it cannot read: the plain upload's
    abort, judged there)."""
    entry = node.dictionary.entry(index, sub)
    try:
        size = len(encode(entry.dtype, node.dictionary.read(index, sub)))
    except SdoAbort:
        return True
    return bool(pst) and size <= pst


def _abort_is(answer: bytes, code: int, why: str) -> str | None:
    got = int.from_bytes(answer[4:8], "little")
    if answer[0] == ABORT and got == int(code):
        return None
    return f"{why}: expected abort 0x{int(code):08X}, got {answer.hex(' ')}"
