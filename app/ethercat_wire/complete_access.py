"""SDO complete access (ETG.1000.6, bit 0x10 of an initiate command): a whole object at once.

The layout is the one SOEM's ``ecx_readPDOmapCA`` reads (``ec_PDOassignt``: ``uint8 n, pad,
uint16[]``) and SOES (``esc_coe.c``) writes: sub 0 of an object with subs as U8 padded to 16
bits, then each sub in order; a bit type (BOOLEAN) goes into the next free bit, any other
starts on the next byte; an object without subs is its value alone. The object ends at the sub
its sub 0 names (the value it holds for an upload, the downloaded one for a download, ETG.1020
§12.2); subs the dictionary does not have in that range take no room. The access starts at
sub 0 (sub 0 included) or 1 (left out); any other start is 0x06010000, an object with a string
0x06010004 (its length is not the type's).

Every sub goes through the face's ``upload_raw`` / ``download_raw``, the path of a single SDO,
so the model's own access, range and state checks and abort codes apply. A download is all or
nothing: every value is checked against its entry (access, type range) before the first write;
then the subs are written sub 0 first, and if the model refuses one (a state, an ident), the
subs already written get their old values back through the same path, in reverse order, and
the abort is the refused sub's. A read-only sub may be sent with the value it holds (a master
writes the whole object back) and is then skipped; another value is 0x06010002.
"""

from __future__ import annotations

import logging
from typing import Any

from app.ethercat_wire.faces.base import Face
from devices.od import AbortCode, DataType, OdEntry, SdoAbort, decode

logger = logging.getLogger(__name__)

VARIABLE_LENGTH = (DataType.VISIBLE_STRING, DataType.OCTET_STRING)
SUB0_PADDED_BITS = 16
Field = tuple[OdEntry, int, int]  # entry, bit offset, bits it takes


def _entries(face: Face, model: Any, index: int, start: int) -> list[OdEntry]:
    if start > 1:
        raise SdoAbort(AbortCode.UNSUPPORTED_ACCESS, index, start)
    entries = [e for e in face.objects(model) if e.index == index]
    if not entries:
        raise SdoAbort(AbortCode.NO_OBJECT, index, start)
    if all(e.sub != start for e in entries):
        raise SdoAbort(AbortCode.NO_SUBINDEX, index, start)
    return entries


def _fields(entries: list[OdEntry], start: int, count: int) -> list[Field]:
    """Where each transferred sub sits: ``count`` is sub 0's value (ignored for a VAR)."""
    index = entries[0].index
    has_subs = any(e.sub > 0 for e in entries)
    chosen = [e for e in entries if start <= e.sub and (not has_subs or e.sub <= count)]
    out: list[Field] = []
    bit = 0
    for entry in chosen:
        if entry.dtype in VARIABLE_LENGTH:
            raise SdoAbort(AbortCode.CA_VARIABLE_LENGTH, index, start)
        width = SUB0_PADDED_BITS if entry.sub == 0 and has_subs else entry.bit_length
        if entry.bit_length % 8 == 0:
            bit = -(-bit // 8) * 8  # a byte type starts on a byte
        out.append((entry, bit, width))
        bit += width
    return out


def _size(fields: list[Field]) -> int:
    return -(-max((bit + width for _e, bit, width in fields), default=0) // 8)


def _value_bytes(entry: OdEntry, bits: int) -> bytes:
    return bits.to_bytes(max(1, entry.bit_length // 8), "little")


def upload(face: Face, model: Any, index: int, start: int) -> bytes:
    """The bytes of a complete-access upload of ``index`` from sub ``start`` (0 or 1)."""
    entries = _entries(face, model, index, start)
    count = int.from_bytes(face.upload_raw(model, index, 0), "little")
    fields = _fields(entries, start, count)
    image = 0
    for entry, bit, _width in fields:
        raw = int.from_bytes(face.upload_raw(model, index, entry.sub), "little")
        image |= (raw & ((1 << entry.bit_length) - 1)) << bit
    return image.to_bytes(_size(fields), "little")


def download(face: Face, model: Any, index: int, start: int, data: bytes) -> None:
    """A complete-access download of ``data`` into ``index`` from sub ``start`` (0 or 1)."""
    entries = _entries(face, model, index, start)
    if start == 0 and any(e.sub > 0 for e in entries):
        count = data[0] if data else 0
    else:
        count = int.from_bytes(face.upload_raw(model, index, 0), "little")
    fields = _fields(entries, start, count)
    if len(data) != _size(fields):
        code = AbortCode.LENGTH_TOO_HIGH if len(data) > _size(fields) else \
            AbortCode.LENGTH_TOO_LOW
        raise SdoAbort(code, index, start)
    image = int.from_bytes(data, "little")
    writes = _checked_writes(face, model, fields, image)
    done: list[tuple[int, bytes]] = []
    try:
        for sub, raw, old in writes:
            face.download_raw(model, index, sub, raw)
            done.append((sub, old))
    except SdoAbort:
        _put_back(face, model, index, done)
        raise


def _checked_writes(face: Face, model: Any, fields: list[Field],
                    image: int) -> list[tuple[int, bytes, bytes]]:
    """(sub, new bytes, old bytes) of every sub to write, once all passed their entry's checks
    (nothing is written when one does not)."""
    writes = []
    for entry, bit, _width in fields:
        raw = _value_bytes(entry, image >> bit & ((1 << entry.bit_length) - 1))
        old = face.upload_raw(model, entry.index, entry.sub) if entry.access.readable else b""
        if not entry.access.writable:
            if raw != old:
                raise SdoAbort(AbortCode.READ_ONLY, entry.index, entry.sub)
            continue
        try:
            entry.check_value(decode(entry.dtype, raw))
        except SdoAbort as exc:
            raise SdoAbort(exc.code, entry.index, entry.sub) from None
        writes.append((entry.sub, raw, old))
    return writes


def _put_back(face: Face, model: Any, index: int, done: list[tuple[int, bytes]]) -> None:
    for sub, old in reversed(done):
        if not old:
            continue  # a write-only sub: nothing to put back
        try:
            face.download_raw(model, index, sub, old)
        except SdoAbort as exc:  # the model refuses its own old value: say so, go on
            logger.warning("%s: 0x%04X:%d not put back after a refused complete access: %s",
                           model.device_id, index, sub, exc)
