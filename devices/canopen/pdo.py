"""PDO communication and mapping parameters, the mapping rules, and when a PDO goes out.

Seed 004 ch. 4: 4 RPDO (0x1400-0x1403 / 0x1600-0x1603) and 4 TPDO (0x1800-0x1803 /
0x1A00-0x1A03); "La mappatura di un PDO deve rispettare i parametri di lunghezza, mappabilità,
esistenza dell'oggetto da mappare. Nello stesso PDO è possibile mappare oggetti per una
lunghezza massima di 8 Byte; la granularità è di 1 Byte. Per eliminare una mappatura bisogna
agire con il NumOfEntries del PDO." Transmission types ("Servizio PDO"): TPDO 254/255 with an
event timer = asynchronous, sent on the timer or an event, never sooner than the inhibit time
after the previous one; 0 = synchronous acyclic, sent at the Sync after an event; 1..240 = sent
every n Syncs. RPDO 254/255 are applied at once, 0..240 at the next Sync.

Mapping entries follow DS 301 (index 16 bits, sub-index 8, length in bits 8): a change starts
with sub 0 = 0, then the entries, then sub 0 = their number (the seed's interpolator example
does exactly that).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from devices.canopen.dictionary import CanOpenDictionary
from devices.od import (
    AbortCode,
    DataType,
    ObjectDictionary,
    OdEntry,
    SdoAbort,
    decode,
    encode,
)

RPDO_COMM, RPDO_MAP, TPDO_COMM, TPDO_MAP = 0x1400, 0x1600, 0x1800, 0x1A00
COB_INVALID = 0x8000_0000  # bit 31: PDO not valid ("un MSB settato a 1 significa NON valido")
COB_NO_RTR = 0x4000_0000  # bit 30: no remote request allowed (TPDO)
COB_EXTENDED = 0x2000_0000  # bit 29: 29-bit identifier, not supported by the drive
MAX_ENTRIES = 8
MAX_BITS = 64  # eight bytes
TYPE_SYNC_ACYCLIC = 0
LAST_SYNC_CYCLIC = 240
ASYNC_TYPES = (254, 255)
# The drive's PDO modes: "sincrono (ciclico e aciclico), asincrono" (ch. 4): no RTR-only types.
VALID_TYPES = frozenset(range(0, LAST_SYNC_CYCLIC + 1)) | frozenset(ASYNC_TYPES)
# DS 301 dummy mapping: the data type indices, in RPDOs only, byte-sized ones (granularity 8).
DUMMY_BITS: dict[int, int] = {0x0002: 8, 0x0003: 16, 0x0004: 32, 0x0005: 8, 0x0006: 16,
                              0x0007: 32}

# Default COB-IDs of the predefined connection set (DS 301): RPDO1 of node 1 is 513 = 0x201, as
# the interpolator example says ("il numero 513 è il COB ID di default per il Receive PDO 1").
RPDO_COB_BASE = (0x200, 0x300, 0x400, 0x500)
TPDO_COB_BASE = (0x180, 0x280, 0x380, 0x480)
# Default mappings: the PDO contents ch. 5 prints for the same drive on EtherCAT (ch. 4 prints
# none). Only RPDO1 and TPDO1 are valid at power-up; the others wait to be enabled.
DEFAULT_RPDO_MAPS: tuple[tuple[int, ...], ...] = (
    (0x6040_0010, 0x60C1_0120),  # controlword + interpolation set-point
    (0x6040_0010, 0x6060_0008),  # controlword + modes of operation
    (0x6040_0010, 0x607A_0020),  # controlword + target position
    (0x6040_0010, 0x60FF_0020),  # controlword + target velocity
)
DEFAULT_TPDO_MAPS: tuple[tuple[int, ...], ...] = (
    (0x6041_0010,),  # statusword
    (0x6041_0010, 0x6061_0008),  # statusword + modes of operation display
    (0x6041_0010, 0x6064_0020),  # statusword + position actual value
    (0x6041_0010, 0x606C_0020),  # statusword + velocity actual value
)
DEFAULT_TYPE = 255
VALID_AT_POWER_UP = 1  # PDO number

_NOT_NUMBERS = frozenset({DataType.VISIBLE_STRING, DataType.OCTET_STRING})
Lookup = Callable[[int, int], OdEntry]  # raises SdoAbort when the object does not exist


def split_entry(value: int) -> tuple[int, int, int]:
    """(index, sub-index, length in bits) of a mapping entry."""
    return value >> 16, (value >> 8) & 0xFF, value & 0xFF


@dataclass
class Pdo:
    """One PDO: its communication record, its mapping, and its transmission bookkeeping."""

    number: int  # 1..4
    receive: bool
    cob_id: int
    trans_type: int = DEFAULT_TYPE
    inhibit_100us: int = 0  # TPDO sub 3
    compatibility: int = 0  # TPDO sub 4 (reserved in DS 301; stored)
    event_timer_ms: int = 0  # TPDO sub 5
    entries: list[int] = field(default_factory=lambda: [0] * MAX_ENTRIES)
    count: int = 0
    # runtime
    last_sent_us: int | None = None
    last_data: bytes | None = None
    # the event timer runs from here: the last send, or a later write of sub 5 ("Se viene
    # scritto un valore maggiore di 0, il timer si attiva", ch. 4 l. 2236)
    timer_from_us: int | None = None
    syncs: int = 0
    buffered: bytes | None = None  # synchronous RPDO data waiting for the next Sync
    sampled: bytes | None = None  # synchronous TPDO data recorded at the last Sync (for RTR)
    # (dictionary, count, entries, [(entry, stored values, key)]) for pack_planned; a cache
    _plan: tuple[Any, ...] | None = field(default=None, repr=False, compare=False)
    # (the configuration it was made for, describe()'s dict); a cache
    _described: tuple[Any, dict[str, object]] | None = field(default=None, repr=False,
                                                              compare=False)

    @classmethod
    def default(cls, number: int, receive: bool, node_id: int) -> Pdo:
        base = (RPDO_COB_BASE if receive else TPDO_COB_BASE)[number - 1]
        cob_id = base + node_id
        if number != VALID_AT_POWER_UP:
            cob_id |= COB_INVALID
        mapping = (DEFAULT_RPDO_MAPS if receive else DEFAULT_TPDO_MAPS)[number - 1]
        entries = [*mapping, *[0] * (MAX_ENTRIES - len(mapping))]
        return cls(number, receive, cob_id, entries=entries, count=len(mapping))

    @property
    def name(self) -> str:
        return f"{'RPDO' if self.receive else 'TPDO'}{self.number}"

    @property
    def comm_index(self) -> int:
        return (RPDO_COMM if self.receive else TPDO_COMM) + self.number - 1

    @property
    def map_index(self) -> int:
        return (RPDO_MAP if self.receive else TPDO_MAP) + self.number - 1

    @property
    def valid(self) -> bool:
        return not self.cob_id & COB_INVALID

    @property
    def can_id(self) -> int:
        return self.cob_id & 0x7FF

    @property
    def mapped(self) -> list[int]:
        return self.entries[:self.count]

    @property
    def length(self) -> int:
        """Bytes of the mapped data."""
        return sum(split_entry(e)[2] for e in self.mapped) // 8

    @property
    def synchronous(self) -> bool:
        return self.trans_type <= LAST_SYNC_CYCLIC

    def restart(self) -> None:
        """Entering Operational: async TPDOs go out once with their first value."""
        self.last_sent_us = None
        self.last_data = None
        self.timer_from_us = None
        self.syncs = 0
        self.buffered = None
        self.sampled = None

    # ---- SDO writes of the communication record -----------------------------------------
    def set_cob_id(self, value: int) -> None:
        if value & COB_EXTENDED or value & 0x1FFF_F800:
            raise SdoAbort(AbortCode.VALUE_RANGE, self.comm_index, 1)
        self.cob_id = value
        self.restart()

    def set_event_timer(self, value: int, now_us: int) -> None:
        """Sub 5: the timer starts at the write; it fires one period later."""
        self.event_timer_ms = value
        if self.last_sent_us is not None:  # else the first send is an event anyway
            self.timer_from_us = now_us

    def set_type(self, value: int) -> None:
        if value not in VALID_TYPES:
            raise SdoAbort(AbortCode.VALUE_RANGE, self.comm_index, 2)
        self.trans_type = value
        self.syncs = 0
        self.sampled = None  # a record from an earlier synchronous spell is not this one's

    # ---- SDO writes of the mapping -------------------------------------------------------
    def set_count(self, value: int, lookup: Lookup) -> None:
        if value > MAX_ENTRIES:
            raise SdoAbort(AbortCode.VALUE_TOO_HIGH, self.map_index, 0)
        bits = 0
        for sub in range(1, value + 1):
            entry = self.entries[sub - 1]
            if entry == 0:
                raise SdoAbort(AbortCode.NOT_MAPPABLE, self.map_index, sub)
            self.check_entry(entry, sub, lookup)
            bits += split_entry(entry)[2]
        if bits > MAX_BITS:
            raise SdoAbort(AbortCode.PDO_TOO_LONG, self.map_index, 0)
        self.count = value
        self.restart()

    def set_entry(self, sub: int, value: int, lookup: Lookup) -> None:
        if self.count != 0:  # DS 301: sub 0 = 0 first ("agire con il NumOfEntries")
            raise SdoAbort(AbortCode.UNSUPPORTED_ACCESS, self.map_index, sub)
        if value != 0:
            self.check_entry(value, sub, lookup)
        self.entries[sub - 1] = value

    def check_entry(self, value: int, sub: int, lookup: Lookup) -> None:
        """Existence, mappability, direction, length = the object's, byte granularity."""
        index, obj_sub, bits = split_entry(value)
        refuse = SdoAbort(AbortCode.NOT_MAPPABLE, self.map_index, sub)
        if self.receive and index in DUMMY_BITS and obj_sub == 0:
            if bits != DUMMY_BITS[index]:
                raise refuse
            return
        try:
            obj = lookup(index, obj_sub)
        except SdoAbort:
            raise refuse from None
        usable = obj.access.writable if self.receive else obj.access.readable
        if not (obj.pdo_mappable and usable) or obj.dtype in _NOT_NUMBERS:
            raise refuse
        if bits != obj.bit_length or bits % 8:
            raise refuse

    # ---- data ----------------------------------------------------------------------------
    def pack(self, lookup: Lookup, read: Callable[[int, int], object]) -> bytes:
        """The TPDO's data from the current object values (mapping order, little endian)."""
        out = bytearray()
        for value in self.mapped:
            index, sub, _bits = split_entry(value)
            out += encode(lookup(index, sub).dtype, read(index, sub))
        return bytes(out)

    def pack_planned(self, dictionary: Any) -> bytes:
        """:meth:`pack` with ``dictionary.entry`` / ``dictionary.peek``, the lookups made once
        per dictionary and mapping (a TPDO is packed every step in Operational): the same
        getters in the same order, the same bytes, the same exceptions."""
        plan = self._plan
        if plan is None or plan[0] is not dictionary or plan[1] != self.count \
                or plan[2] != self.entries:
            try:
                lookups = self._lookups(dictionary)
            except SdoAbort:  # an object that does not exist: the plain path raises it
                lookups = None
            if lookups is None:
                self._plan = None
                return self.pack(dictionary.entry, dictionary.peek)
            plan = self._plan = (dictionary, self.count, list(self.entries), lookups)
        out = b""
        for entry, values, key in plan[3]:
            dtype, getter = entry.dtype, entry.getter
            out += encode(dtype, getter() if getter is not None else values[key])
        return out

    def _lookups(self, dictionary: Any) -> list[tuple[OdEntry, dict, tuple[int, int]]] | None:
        """What :meth:`pack` looks up per mapped object: the entry (``dictionary.entry``) and
        where ``dictionary.peek`` finds a stored value (the owning dictionary's values);
        None when a dictionary reads its own way (only the plain ones are planned)."""
        if type(dictionary) is not CanOpenDictionary:
            return None
        out = []
        for value in self.mapped:
            index, sub, _bits = split_entry(value)
            owner = dictionary.owner(index, sub)
            if type(owner) is not ObjectDictionary:
                return None
            out.append((owner.entry(index, sub), owner._values, (index, sub)))
        return out

    def unpack(self, data: bytes, lookup: Lookup) -> list[tuple[int, int, object]]:
        """(index, sub, value) of each mapped object in an RPDO's data; dummies skipped."""
        out: list[tuple[int, int, object]] = []
        offset = 0
        for value in self.mapped:
            index, sub, bits = split_entry(value)
            size = bits // 8
            chunk = data[offset:offset + size]
            offset += size
            if index in DUMMY_BITS and sub == 0:
                continue
            out.append((index, sub, decode(lookup(index, sub).dtype, chunk)))
        return out

    def describe(self) -> dict[str, object]:
        """Snapshot form for views (one dict per configuration: every snapshot asks, and the
        configuration changes only by an SDO write)."""
        key = (self.cob_id, self.trans_type, self.inhibit_100us, self.event_timer_ms,
               tuple(self.mapped))
        cached = self._described
        if cached is not None and cached[0] == key:
            return cached[1]
        described = self._describe()
        self._described = (key, described)
        return described

    def _describe(self) -> dict[str, object]:
        return {
            "pdo": self.name, "cob_id": f"0x{self.cob_id:08X}", "can_id": f"0x{self.can_id:03X}",
            "valid": self.valid, "type": self.trans_type,
            **({} if self.receive else {"inhibit_100us": self.inhibit_100us,
                                        "event_timer_ms": self.event_timer_ms}),
            "mapping": [f"0x{index:04X}:{sub:02X}/{bits}"
                        for index, sub, bits in map(split_entry, self.mapped)],
        }
