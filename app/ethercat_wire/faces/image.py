"""Process images from PDO mapping objects: bit-exact packing of the mapped entries.

A master sizes a slave's SM2 / SM3 from the mapping it reads (ETG.1000.6: 0x1C12 / 0x1C13
list the PDOs, each 0x16xx / 0x1Axx sub n = ``index << 16 | sub << 8 | bits``): the entries of
all assigned PDOs one after another, bit by bit, the SM length rounded up to whole bytes at the
end (SOEM's ``ecx_readPDOmap`` does exactly this). A 1-bit entry therefore takes one bit, not
a byte; an entry with index 0 is a gap of ``bits`` bits. Values are little endian, LSB first.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from app.ethercat_wire.description import Pdo, PdoEntry
from devices.od import DataType, OdEntry

_SIGNED = frozenset({DataType.INTEGER8, DataType.INTEGER16, DataType.INTEGER32})

Peek = Callable[[int, int], Any]  # (index, sub) -> value, no access checks
Lookup = Callable[[int, int], OdEntry]  # (index, sub) -> entry (raises SdoAbort)


def split_entry(value: int) -> tuple[int, int, int]:
    """(index, sub, bits) of a mapping entry."""
    return value >> 16 & 0xFFFF, value >> 8 & 0xFF, value & 0xFF


def assigned(peek: Peek, assign_index: int) -> list[int]:
    """The PDO indices an assignment object (0x1C12 / 0x1C13) lists, in order."""
    return [int(peek(assign_index, sub)) for sub in range(1, int(peek(assign_index, 0)) + 1)]


def read_pdo(peek: Peek, lookup: Lookup, pdo_index: int) -> Pdo:
    """One PDO as its mapping object says, with the mapped objects' names and types (gaps
    unnamed, untyped)."""
    entries = []
    for sub in range(1, int(peek(pdo_index, 0)) + 1):
        index, e_sub, bits = split_entry(int(peek(pdo_index, sub)))
        if not index:
            entries.append(PdoEntry(0, e_sub, bits, ""))
            continue
        obj = lookup(index, e_sub)
        # The object's own type (signed where it is), as an ESI names it; a mapping shorter
        # than the type has no ETG name of its own and is typed by its length
        data_type = obj.dtype.short if bits == obj.bit_length else ""
        entries.append(PdoEntry(index, e_sub, bits, obj.name, data_type))
    return Pdo(pdo_index, str(lookup(pdo_index, 0).name), tuple(entries))


def read_pdos(peek: Peek, lookup: Lookup, pdo_indices: Iterable[int]) -> tuple[Pdo, ...]:
    return tuple(read_pdo(peek, lookup, index) for index in pdo_indices)


def bit_size(pdos: Sequence[Pdo]) -> int:
    return sum(e.bits for pdo in pdos for e in pdo.entries)


def byte_size(pdos: Sequence[Pdo]) -> int:
    return (bit_size(pdos) + 7) // 8


@dataclass(frozen=True)
class Field:
    """One mapped object in the image: its bit offset and width."""

    index: int
    sub: int
    offset: int  # bits from the image start
    bits: int


def fields(pdos: Sequence[Pdo]) -> list[Field]:
    """Every mapped object (gaps left out) with its place in the image."""
    out, offset = [], 0
    for pdo in pdos:
        for e in pdo.entries:
            if e.index:
                out.append(Field(e.index, e.sub, offset, e.bits))
            offset += e.bits
    return out


def pack(pdos: Sequence[Pdo], peek: Peek) -> bytes:
    """The image of the current object values (an integer masked to its width)."""
    return pack_fields(fields(pdos), byte_size(pdos), peek)


def pack_fields(mapped: Sequence[Field], size: int, peek: Peek) -> bytes:
    word = 0
    for f in mapped:
        word |= (int(peek(f.index, f.sub)) & ((1 << f.bits) - 1)) << f.offset
    return word.to_bytes(size, "little")


def unpack(pdos: Sequence[Pdo], data: bytes, lookup: Lookup) -> list[tuple[int, int, int]]:
    """(index, sub, value) of every mapped object in ``data``; signed types sign-extended."""
    return unpack_fields(fields(pdos), data, lookup)


def unpack_fields(mapped: Sequence[Field], data: bytes, lookup: Lookup
                  ) -> list[tuple[int, int, int]]:
    word = int.from_bytes(data, "little")
    out = []
    for f in mapped:
        raw = word >> f.offset & ((1 << f.bits) - 1)
        if lookup(f.index, f.sub).dtype in _SIGNED and raw >> (f.bits - 1):
            raw -= 1 << f.bits
        out.append((f.index, f.sub, raw))
    return out


def changed(pdos: Sequence[Pdo], before: bytes | None, after: bytes) -> set[tuple[int, int]]:
    """The objects whose bits differ between two images (all of them without ``before``)."""
    if before is None or len(before) != len(after):
        return {(f.index, f.sub) for f in fields(pdos)}
    diff = int.from_bytes(before, "little") ^ int.from_bytes(after, "little")
    return {(f.index, f.sub) for f in fields(pdos)
            if diff >> f.offset & ((1 << f.bits) - 1)}
