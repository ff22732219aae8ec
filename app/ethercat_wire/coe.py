"""CoE over the mailbox, for every slave of the line: SDO, SDO information, emergencies.

One :class:`CoeServer` per slave turns a complete mailbox message the master wrote into SM0
(header included, as process B forwards it) into the mailbox messages that go back through
SM1, reading and writing the slave model through its face (its object dictionary, its own
access and range checks, its DS301 abort codes). Layouts are ETG.1000.6 as SOEM reads them
(``ec_coe.c``); the pitfalls of /work/shared/docs/ethercat-wire-notes.md are followed:

- mailbox header ``length u16, address u16, channel/priority u8, type | counter << 4``;
  CoE header ``number | service << 12``;
- upload answered expedited (``0x43 | (4 - n) << 2``) up to four bytes, else normal (``0x41``,
  u32 size, data) and, past one mailbox, in segments the master fetches with ``0x60 / 0x70``;
  download answered ``0x60``, segments ``0x20 | toggle``;
- an abort (``0x80``, u32 code) travels with CoE service 2: SOEM takes an abort sent as a
  service-3 response for a malformed answer (``PacketError(1, 3)``);
- the sizes are the object's type: a download of the wrong length aborts 0x0607001x
  (the drive keeps its own ch. 4 length rule through its face);
- complete access (bit 0x10 of an initiate) is served for a face whose CoE details announce
  it (bit 0x20), else aborted 0x06010000; the whole object's layout, and the rule that a
  download is all or nothing, are :mod:`app.ethercat_wire.complete_access`'s. The answers echo
  the bit; a long one is segmented as any other.

The command specifiers are the ``canopen`` library's constants. Its ``SdoServer`` is not reused:
it serves CAN frames (8 bytes, 7-byte segments, a toggle per CAN segment) while a CoE normal
transfer carries up to a mailbox of data in its initiate message and segments of mailbox size,
and CoE adds SDO information and emergencies, which it has no notion of (docs/ethercat-wire.md).
"""

from __future__ import annotations

import logging
import struct
from dataclasses import dataclass, field
from typing import Any

from canopen.sdo import constants as cs

from app.ethercat_wire import complete_access
from app.ethercat_wire.faces.base import COE_COMPLETE_ACCESS, MAILBOX_SIZE, Face, NoAnswer
from devices.od import AbortCode, Access, OdEntry, SdoAbort

logger = logging.getLogger(__name__)

MBX_HEADER = struct.Struct("<HHBB")  # length, address, channel/priority, type | counter << 4
MBX_TYPE_ERROR, MBX_TYPE_COE = 0x00, 0x03
COE_EMERGENCY, COE_SDO_REQUEST, COE_SDO_RESPONSE, COE_SDO_INFO = 0x1, 0x2, 0x3, 0x8
COMPLETE_ACCESS = 0x10  # in an initiate request (0x50 upload, 0x31 download)
SDO_HEADER = struct.Struct("<HBHB")  # CoE header, command, index, sub
SDO_FIXED = 10  # CoE header 2 + command 1 + index 2 + sub 1 + data/size 4
SEGMENT_FIXED = 3  # CoE header 2 + command 1
SEGMENT_MIN_DATA = 7  # a shorter last segment is padded; the command says how many are unused

# ETG.1000.6 mailbox error detail codes
MBXERR_SERVICE_NOT_SUPPORTED, MBXERR_UNSUPPORTED_PROTOCOL, MBXERR_SIZE_TOO_SHORT = 0x04, 0x02, 0x06

# SDO information (ETG.1000.6 5.6.3): opcodes; bit 7 = more fragments follow
INFO_LIST_REQ, INFO_LIST_RES = 0x01, 0x02
INFO_OD_REQ, INFO_OD_RES = 0x03, 0x04
INFO_OE_REQ, INFO_OE_RES = 0x05, 0x06
INFO_ERROR = 0x07
INFO_INCOMPLETE = 0x80
INFO_FIXED = 6  # CoE header 2 + opcode 1 + reserved 1 + fragments left 2
LIST_LENGTHS, LIST_ALL, LIST_RX, LIST_TX, LIST_BACKUP, LIST_SETTINGS = range(6)
OBJECT_VAR, OBJECT_ARRAY, OBJECT_RECORD = 0x07, 0x08, 0x09
# Object access word of an entry description (ETG.1000.6 Table 59)
READ_ALL, WRITE_ALL, RXPDO_MAPPABLE, TXPDO_MAPPABLE = 0x0007, 0x0038, 0x0040, 0x0080
WRITE_PREOP = 0x0008
VALUE_INFO_BASIC = 0x07  # the value-info bits a description answers (no unit/default/min/max)


def mailbox_message(mbx_type: int, counter: int, payload: bytes) -> bytes:
    return MBX_HEADER.pack(len(payload), 0, 0, mbx_type | counter << 4) + payload


def coe_header(service: int) -> bytes:
    return struct.pack("<H", service << 12)


def access_word(entry: OdEntry) -> int:
    access = entry.access
    write = WRITE_PREOP if access is Access.RW_PREOP else WRITE_ALL if access.writable else 0
    word = (READ_ALL if access.readable else 0) | write
    if entry.pdo_mappable:
        tx = entry.access is not Access.RW if entry.pdo_input is None else entry.pdo_input
        word |= TXPDO_MAPPABLE if tx else RXPDO_MAPPABLE
    return word


@dataclass
class _Upload:
    index: int
    sub: int
    rest: bytes
    toggle: int = 0


@dataclass
class _Download:
    index: int
    sub: int
    size: int
    data: bytearray = field(default_factory=bytearray)
    toggle: int = 0
    whole: bool = False  # a complete access


class CoeServer:
    """The CoE side of one slave's mailbox. Runs in the simulation thread (it reads models)."""

    def __init__(self, face: Face, model: Any, mailbox_size: int = MAILBOX_SIZE) -> None:
        self.face = face
        self.model = model
        self.mailbox_size = mailbox_size  # SM1 length: a reply never exceeds it
        self.counter = 0
        self._upload: _Upload | None = None
        self._download: _Download | None = None

    # ---- framing ---------------------------------------------------------------------------
    def _next_counter(self) -> int:
        self.counter = self.counter % 7 + 1  # 1..7; 0 is reserved
        return self.counter

    def _coe(self, payload: bytes) -> bytes:
        return mailbox_message(MBX_TYPE_COE, self._next_counter(), payload)

    def _mailbox_error(self, detail: int) -> list[bytes]:
        payload = struct.pack("<HH", 0x0001, detail)  # type 1 = mailbox command
        return [mailbox_message(MBX_TYPE_ERROR, self._next_counter(), payload)]

    def emergency(self, frame: bytes) -> bytes:
        """An 8-byte emergency (code LE16, register, 5 bytes) as a CoE mailbox message."""
        if len(frame) != 8:
            raise ValueError(f"an emergency frame has 8 bytes, got {len(frame)}")
        return self._coe(coe_header(COE_EMERGENCY) + bytes(frame))

    def handle(self, message: bytes) -> list[bytes]:
        """The reply messages to one request (none: the slave does not answer now)."""
        if len(message) < MBX_HEADER.size + 2:
            return self._mailbox_error(MBXERR_SIZE_TOO_SHORT)
        length, _address, _prio, type_counter = MBX_HEADER.unpack_from(message)
        body = bytes(message[MBX_HEADER.size:MBX_HEADER.size + length])
        if type_counter & 0x0F != MBX_TYPE_COE or self.face.bootstrap_mailbox(self.model):
            # BOOT runs the bootstrap mailbox, for FoE only (ETG.1000.6): CoE is refused
            # there as any protocol FieldRig does not serve
            return self._mailbox_error(MBXERR_UNSUPPORTED_PROTOCOL)
        if len(body) < 2:
            return self._mailbox_error(MBXERR_SIZE_TOO_SHORT)
        service = struct.unpack_from("<H", body)[0] >> 12
        try:
            if service == COE_SDO_REQUEST:
                if len(body) < SDO_HEADER.size:
                    return self._mailbox_error(MBXERR_SIZE_TOO_SHORT)
                reply = self._sdo(body)
                return [self._coe(reply)] if reply else []
            if service == COE_SDO_INFO:
                if len(body) < INFO_FIXED:
                    return self._mailbox_error(MBXERR_SIZE_TOO_SHORT)
                return [self._coe(p) for p in self._info(body)]
        except NoAnswer as exc:
            logger.debug("%s: no CoE answer: %s", self.model.device_id, exc)
            return []
        return self._mailbox_error(MBXERR_SERVICE_NOT_SUPPORTED)

    # ---- SDO -------------------------------------------------------------------------------
    def _sdo(self, body: bytes) -> bytes:
        _coe, command, index, sub = SDO_HEADER.unpack_from(body)
        ccs = command & 0xE0
        if ccs == cs.REQUEST_SEGMENT_UPLOAD:
            return self._segment_upload(command)
        if ccs == cs.REQUEST_SEGMENT_DOWNLOAD:
            return self._segment_download(command, body)
        self._upload = self._download = None  # a new transfer ends any other
        if ccs == cs.REQUEST_ABORTED:
            return b""  # never sent: the caller drops an empty answer
        try:
            whole = bool(command & COMPLETE_ACCESS)
            if whole and (sub > 1 or not self.face.coe_details & COE_COMPLETE_ACCESS):
                raise SdoAbort(AbortCode.UNSUPPORTED_ACCESS, index, sub)
            if ccs == cs.REQUEST_UPLOAD:
                return self._initiate_upload(index, sub, whole)
            if ccs == cs.REQUEST_DOWNLOAD:
                return self._initiate_download(command, index, sub, body)
            raise SdoAbort(AbortCode.INVALID_COMMAND, index, sub)
        except SdoAbort as exc:
            return self.abort(index, sub, exc.code)

    def abort(self, index: int, sub: int, code: int) -> bytes:
        """An abort: CoE service 2 (SOEM rejects one sent as a response, see module doc)."""
        self._upload = self._download = None
        return SDO_HEADER.pack(COE_SDO_REQUEST << 12, cs.REQUEST_ABORTED, index, sub) + \
            struct.pack("<I", int(code))

    def _response(self, command: int, index: int, sub: int, data: bytes = b"") -> bytes:
        return SDO_HEADER.pack(COE_SDO_RESPONSE << 12, command, index, sub) + data

    def _initiate_upload(self, index: int, sub: int, whole: bool = False) -> bytes:
        if whole:
            data = complete_access.upload(self.face, self.model, index, sub)
        else:
            data = self.face.upload_raw(self.model, index, sub)
        ca = COMPLETE_ACCESS if whole else 0
        if 0 < len(data) <= 4:
            command = cs.RESPONSE_UPLOAD | cs.EXPEDITED | cs.SIZE_SPECIFIED | (4 - len(data)) << 2
            return self._response(command | ca, index, sub, data.ljust(4, b"\0"))
        room = self.mailbox_size - MBX_HEADER.size - SDO_FIXED
        first, rest = data[:room], data[room:]
        if rest:
            self._upload = _Upload(index, sub, rest)
        return self._response(cs.RESPONSE_UPLOAD | cs.SIZE_SPECIFIED | ca, index, sub,
                              struct.pack("<I", len(data)) + first)

    def _write(self, whole: bool, index: int, sub: int, data: bytes) -> None:
        if whole:
            complete_access.download(self.face, self.model, index, sub, data)
        else:
            self.face.download_raw(self.model, index, sub, data)

    def _segment_upload(self, command: int) -> bytes:
        up = self._upload
        if up is None:
            return self.abort(0, 0, AbortCode.INVALID_COMMAND)
        toggle = command & cs.TOGGLE_BIT
        if toggle != up.toggle:
            return self.abort(up.index, up.sub, AbortCode.TOGGLE_NOT_ALTERNATED)
        room = self.mailbox_size - MBX_HEADER.size - SEGMENT_FIXED
        chunk, up.rest = up.rest[:room], up.rest[room:]
        up.toggle ^= cs.TOGGLE_BIT
        reply = cs.RESPONSE_SEGMENT_UPLOAD | toggle
        if not up.rest:
            self._upload = None
            reply |= cs.NO_MORE_DATA
            if len(chunk) < SEGMENT_MIN_DATA:
                reply |= (SEGMENT_MIN_DATA - len(chunk)) << 1
                chunk = chunk.ljust(SEGMENT_MIN_DATA, b"\0")
        return coe_header(COE_SDO_RESPONSE) + bytes((reply,)) + chunk

    def _initiate_download(self, command: int, index: int, sub: int, body: bytes) -> bytes:
        whole = bool(command & COMPLETE_ACCESS)
        answer = cs.RESPONSE_DOWNLOAD | (COMPLETE_ACCESS if whole else 0)
        if command & cs.EXPEDITED:
            n = 4 - (command >> 2 & 0x03) if command & cs.SIZE_SPECIFIED else 4
            self._write(whole, index, sub, body[6:6 + n])
            return self._response(answer, index, sub, bytes(4))
        if len(body) < SDO_FIXED:
            raise SdoAbort(AbortCode.INVALID_COMMAND, index, sub)
        size = struct.unpack_from("<I", body, 6)[0]
        data = body[SDO_FIXED:]
        if len(data) >= size:
            self._write(whole, index, sub, data[:size])
        else:  # segments follow: refuse a missing or read-only object now, not at the end
            entry = self.face.entry(self.model, index, sub)
            if not whole and not entry.access.writable:  # a whole object may have RW subs
                raise SdoAbort(AbortCode.READ_ONLY, index, sub)
            self._download = _Download(index, sub, size, bytearray(data), whole=whole)
        return self._response(answer, index, sub, bytes(4))

    def _segment_download(self, command: int, body: bytes) -> bytes:
        down = self._download
        if down is None:
            return self.abort(0, 0, AbortCode.INVALID_COMMAND)
        toggle = command & cs.TOGGLE_BIT
        if toggle != down.toggle:
            return self.abort(down.index, down.sub, AbortCode.TOGGLE_NOT_ALTERNATED)
        data = body[SEGMENT_FIXED:]
        last = bool(command & cs.NO_MORE_DATA)
        if last and len(data) == SEGMENT_MIN_DATA:
            data = data[:SEGMENT_MIN_DATA - (command >> 1 & 0x07)]
        down.data += data
        down.toggle ^= cs.TOGGLE_BIT
        if last:
            self._download = None
            if len(down.data) != down.size:
                return self.abort(down.index, down.sub, AbortCode.TYPE_MISMATCH)
            try:
                self._write(down.whole, down.index, down.sub, bytes(down.data))
            except SdoAbort as exc:
                return self.abort(down.index, down.sub, exc.code)
        return coe_header(COE_SDO_RESPONSE) + bytes((cs.RESPONSE_SEGMENT_DOWNLOAD | toggle,)) \
            + bytes(SEGMENT_MIN_DATA)

    # ---- SDO information -------------------------------------------------------------------
    def _entries(self) -> dict[int, list[OdEntry]]:
        out: dict[int, list[OdEntry]] = {}
        for entry in self.face.objects(self.model):
            out.setdefault(entry.index, []).append(entry)
        return out

    def _info(self, body: bytes) -> list[bytes]:
        opcode = body[2] & 0x7F
        data = body[INFO_FIXED:]
        if opcode == INFO_LIST_REQ and len(data) >= 2:
            return self._od_list(struct.unpack_from("<H", data)[0])
        if opcode == INFO_OD_REQ and len(data) >= 2:
            return [self._od_description(struct.unpack_from("<H", data)[0])]
        if opcode == INFO_OE_REQ and len(data) >= 4:
            index, sub, value_info = struct.unpack_from("<HBB", data)
            return [self._entry_description(index, sub, value_info)]
        return [self._info_error(AbortCode.INVALID_COMMAND)]

    @staticmethod
    def _info_message(opcode: int, fragments_left: int, data: bytes) -> bytes:
        op = opcode | (INFO_INCOMPLETE if fragments_left else 0)
        return coe_header(COE_SDO_INFO) + struct.pack("<BBH", op, 0, fragments_left) + data

    def _info_error(self, code: int) -> bytes:
        return self._info_message(INFO_ERROR, 0, struct.pack("<I", int(code)))

    def _od_list(self, list_type: int) -> list[bytes]:
        objects = self._entries()
        lists = {
            LIST_ALL: sorted(objects),
            LIST_RX: sorted(i for i, es in objects.items()
                            if any(access_word(e) & RXPDO_MAPPABLE for e in es)),
            LIST_TX: sorted(i for i, es in objects.items()
                            if any(access_word(e) & TXPDO_MAPPABLE for e in es)),
            LIST_BACKUP: [], LIST_SETTINGS: [],  # no object is flagged backup / settings
        }
        if list_type == LIST_LENGTHS:
            counts = [len(lists[t]) for t in (LIST_ALL, LIST_RX, LIST_TX, LIST_BACKUP,
                                              LIST_SETTINGS)]
            return [self._info_message(INFO_LIST_RES, 0, struct.pack("<6H", 0, *counts))]
        if list_type not in lists:
            return [self._info_error(AbortCode.VALUE_RANGE)]
        words = [list_type, *lists[list_type]]
        per_fragment = (self.mailbox_size - MBX_HEADER.size - INFO_FIXED) // 2
        chunks = [words[i:i + per_fragment] for i in range(0, len(words), per_fragment)]
        return [self._info_message(INFO_LIST_RES, len(chunks) - 1 - n,
                                   struct.pack(f"<{len(c)}H", *c))
                for n, c in enumerate(chunks)]

    def _name(self, name: str, fixed: int) -> bytes:
        room = self.mailbox_size - MBX_HEADER.size - fixed
        return name.encode("latin-1", errors="replace")[:room]

    def _od_description(self, index: int) -> bytes:
        entries = self._entries().get(index)
        if not entries:
            return self._info_error(AbortCode.NO_OBJECT)
        subs = [e for e in entries if e.sub > 0]
        if not subs:
            code, dtype = OBJECT_VAR, int(entries[0].dtype)
        elif len({e.dtype for e in subs}) == 1:
            code, dtype = OBJECT_ARRAY, int(subs[0].dtype)
        else:
            code, dtype = OBJECT_RECORD, 0
        max_sub = max(e.sub for e in entries)
        name = self._name(self.face.object_name(index, entries[0].name), INFO_FIXED + 6)
        return self._info_message(INFO_OD_RES, 0,
                                  struct.pack("<HHBB", index, dtype, max_sub, code) + name)

    def _entry_description(self, index: int, sub: int, value_info: int) -> bytes:
        entries = self._entries().get(index)
        if not entries:
            return self._info_error(AbortCode.NO_OBJECT)
        entry = next((e for e in entries if e.sub == sub), None)
        if entry is None:
            return self._info_error(AbortCode.NO_SUBINDEX)
        name = self._name(entry.name, INFO_FIXED + 10)
        return self._info_message(
            INFO_OE_RES, 0,
            struct.pack("<HBBHHH", index, sub, value_info & VALUE_INFO_BASIC, int(entry.dtype),
                        entry.bit_length, access_word(entry)) + name)
