"""The object dictionary a CANopen master sees: communication objects + the drive's objects.

Seed 004 ch. 4 lists what the drive serves on CANopen. The drive model's dictionary
(devices/servo/od_map.py) also holds objects that ch. 5 adds for EtherCAT only — 0x603F
(error code) and 0x2007 (save): on CANopen they do not exist (abort 0x06020000); the error
code reaches a CANopen master in the emergency message instead. DSP 402 objects of the ch. 4
table that the drive model leaves out (0x6504, 0x6505, 0x67FF) come from
:func:`~devices.canopen.comm_objects.build_profile_extras`, unless the drive has them.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from devices.od import AbortCode, ObjectDictionary, OdEntry, SdoAbort

COE_ONLY = frozenset({0x603F, 0x2007})  # ch. 5 objects, absent from the ch. 4 table


class CanOpenDictionary:
    """One lookup over several dictionaries; an index belongs to the first that has it."""

    def __init__(self, comm: ObjectDictionary, drive: ObjectDictionary,
                 extras: ObjectDictionary) -> None:
        self._owner: dict[int, ObjectDictionary] = {}
        self._subs: dict[int, list[OdEntry]] = {}
        for od, hide in ((comm, frozenset()), (drive, COE_ONLY), (extras, frozenset())):
            mine: dict[int, list[OdEntry]] = {}
            for entry in od:
                mine.setdefault(entry.index, []).append(entry)
            for index, entries in mine.items():
                if index not in hide and index not in self._owner:
                    self._owner[index], self._subs[index] = od, entries

    def owner(self, index: int, sub: int) -> ObjectDictionary:
        od = self._owner.get(index)
        if od is None:
            raise SdoAbort(AbortCode.NO_OBJECT, index, sub)
        return od

    def entry(self, index: int, sub: int) -> OdEntry:
        return self.owner(index, sub).entry(index, sub)

    def read(self, index: int, sub: int) -> Any:
        return self.owner(index, sub).read(index, sub)

    def peek(self, index: int, sub: int) -> Any:
        return self.owner(index, sub).peek(index, sub)

    def write(self, index: int, sub: int, value: Any) -> None:
        self.owner(index, sub).write(index, sub, value)

    def __contains__(self, key: tuple[int, int]) -> bool:
        od = self._owner.get(key[0])
        return od is not None and key in od

    def __iter__(self) -> Iterator[OdEntry]:
        for index in sorted(self._subs):
            yield from self._subs[index]

    def indices(self) -> list[int]:
        return sorted(self._owner)
