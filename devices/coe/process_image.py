"""The process image: the assigned PDOs' data, in assignment order, little endian.

Seed 004 ch. 5: "Per i PDO viene usato l'indirizzamento e la gestione delle FMMU": the master
reads the inputs (TxPDOs 0x1A0x assigned in 0x1C13) and writes the outputs (RxPDOs 0x160x
assigned in 0x1C12) as one block each, the PDOs one after another with their entries in
mapping order (the TwinCAT screen of ch. 5 shows 0x1A02 as 0x6041 at offset 0.0 and 0x6064
at 2.0, 6 bytes). Packing and unpacking one PDO is :class:`devices.canopen.pdo.Pdo`'s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from devices.canopen.pdo import Lookup, Pdo, split_entry


@dataclass(frozen=True)
class ImageEntry:
    """One object in the image: where it sits, for views and for a master's variable list."""

    pdo: int  # 0x1600.. / 0x1A00..
    index: int
    sub: int
    offset: int  # bytes
    bits: int


def layout(pdos: Sequence[Pdo]) -> list[ImageEntry]:
    out, offset = [], 0
    for pdo in pdos:
        for value in pdo.mapped:
            index, sub, bits = split_entry(value)
            out.append(ImageEntry(pdo.map_index, index, sub, offset, bits))
            offset += bits // 8
    return out


def size(pdos: Sequence[Pdo]) -> int:
    return sum(pdo.length for pdo in pdos)


def pack(pdos: Sequence[Pdo], lookup: Lookup, read: Callable[[int, int], Any]) -> bytes:
    """The inputs image from the current object values."""
    return b"".join(pdo.pack(lookup, read) for pdo in pdos)


def unpack(pdos: Sequence[Pdo], data: bytes, lookup: Lookup) -> list[tuple[int, int, Any]]:
    """(index, sub, value) of every mapped output object, in image order (dummies skipped)."""
    if len(data) != size(pdos):
        raise ValueError(f"the outputs image is {size(pdos)} bytes, got {len(data)}")
    out: list[tuple[int, int, Any]] = []
    offset = 0
    for pdo in pdos:
        out += pdo.unpack(data[offset:offset + pdo.length], lookup)
        offset += pdo.length
    return out


def last_writes(writes: list[tuple[int, int, Any]]) -> list[tuple[int, int, Any]]:
    """``writes`` with each object once: its last value, at its last place in image order.

    An object repeats when RxPDOs that share it are assigned together (every default RxPDO
    carries the controlword; ch. 5 "ulteriormente mappare gli oggetti 0x1601"). The drive
    takes the frame's data into its objects and then acts on them once, so it sees the last
    value only, never the earlier ones: a controlword of 0 in 0x1600 and 0x000F in 0x1601
    enables the drive instead of disabling and enabling it in every frame.
    """
    if len(writes) < 2:
        return writes
    last = {(index, sub): n for n, (index, sub, _value) in enumerate(writes)}
    if len(last) == len(writes):  # no object repeats: the usual image
        return writes
    return [w for n, w in enumerate(writes) if last[w[0], w[1]] == n]
