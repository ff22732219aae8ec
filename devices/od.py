"""A CANopen-style object dictionary for device models: entries, types, access rights, aborts.

Pure data and checks; the protocol adapters (CoE mailbox, CANopen SDO server, scenario and UI
``write`` / ``read`` steps) translate into :meth:`ObjectDictionary.read` / ``write`` and turn
:class:`SdoAbort` into the DS301 abort code on their wire. Data type codes are the DS301 ones
so that an EDS export (``canopen.objectdictionary``) is a direct translation.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any


class DataType(enum.IntEnum):
    BOOLEAN = 0x0001
    INTEGER8 = 0x0002
    INTEGER16 = 0x0003
    INTEGER32 = 0x0004
    UNSIGNED8 = 0x0005
    UNSIGNED16 = 0x0006
    UNSIGNED32 = 0x0007
    VISIBLE_STRING = 0x0009
    OCTET_STRING = 0x000A

    @property
    def short(self) -> str:
        """The IEC 61131 name the seeds print (USINT, UINT, DINT, ...)."""
        return _SHORT[self]


_SHORT = {
    DataType.BOOLEAN: "BOOL", DataType.INTEGER8: "SINT", DataType.INTEGER16: "INT",
    DataType.INTEGER32: "DINT", DataType.UNSIGNED8: "USINT", DataType.UNSIGNED16: "UINT",
    DataType.UNSIGNED32: "UDINT", DataType.VISIBLE_STRING: "STRING",
    DataType.OCTET_STRING: "ARRAY OF BYTE",
}


@dataclass(frozen=True)
class TypeNames:
    """How one device's manual names the data types of its object table (the Objects tab's
    Type column): ``names`` covers every DataType, so a table never mixes two manuals' words.
    """

    names: Mapping[DataType, str]
    # An OCTET_STRING of a fixed size (a non-empty default: the size ``bit_length`` and the
    # SDO information service give it), as ``"BYTE[{size}]"``: seed 002 prints "BYTE[23]"
    # for the 0x10F3 messages. None: ``names`` for any size.
    sized_octets: str | None = None

    def of(self, entry: OdEntry) -> str:
        if entry.dtype is DataType.OCTET_STRING and self.sized_octets and entry.default:
            return self.sized_octets.format(size=len(bytes(entry.default)))
        return self.names[entry.dtype]


# Seed 000's words (§6: USINT, UINT, UDINT, BOOL ...), the IEC 61131 names: a device model
# whose manual prints others has a table of its own (DeviceModel.TYPE_NAMES).
IEC_NAMES = TypeNames(_SHORT)

# (struct format, min, max) of the numeric types.
_NUMERIC: dict[DataType, tuple[str, int, int]] = {
    DataType.BOOLEAN: ("<B", 0, 1),
    DataType.INTEGER8: ("<b", -0x80, 0x7F),
    DataType.INTEGER16: ("<h", -0x8000, 0x7FFF),
    DataType.INTEGER32: ("<i", -0x8000_0000, 0x7FFF_FFFF),
    DataType.UNSIGNED8: ("<B", 0, 0xFF),
    DataType.UNSIGNED16: ("<H", 0, 0xFFFF),
    DataType.UNSIGNED32: ("<I", 0, 0xFFFF_FFFF),
}


class Access(enum.Enum):
    RO = "ro"
    RW = "rw"
    WO = "wo"
    CONST = "const"
    # Read in every state, written in PRE-OP only, as seed 001 §9.3.2 prints 0xF030 ("R-WPS",
    # "RO e WRITE in PRE-OP"). The dictionary does not know the ESM state: the entry's setter
    # refuses a write elsewhere; this says so to the Objects tab and to SDO information.
    RW_PREOP = "r-wps"

    @property
    def readable(self) -> bool:
        return self is not Access.WO

    @property
    def writable(self) -> bool:
        return self in (Access.RW, Access.WO, Access.RW_PREOP)


class AbortCode(enum.IntEnum):
    """DS301 SDO abort codes (seed 004 ch. 4, digest §6.3)."""

    TOGGLE_NOT_ALTERNATED = 0x0503_0000
    SDO_TIMEOUT = 0x0504_0000
    INVALID_COMMAND = 0x0504_0001
    UNSUPPORTED_ACCESS = 0x0601_0000
    WRITE_ONLY = 0x0601_0001
    READ_ONLY = 0x0601_0002
    CA_VARIABLE_LENGTH = 0x0601_0004  # ETG.1000.6: complete access to a variable-length object
    NO_OBJECT = 0x0602_0000
    HARDWARE_ERROR = 0x0606_0000
    NOT_MAPPABLE = 0x0604_0041
    PDO_TOO_LONG = 0x0604_0042
    TYPE_MISMATCH = 0x0607_0010
    LENGTH_TOO_HIGH = 0x0607_0012
    LENGTH_TOO_LOW = 0x0607_0013
    NO_SUBINDEX = 0x0609_0011
    VALUE_RANGE = 0x0609_0030
    VALUE_TOO_HIGH = 0x0609_0031
    VALUE_TOO_LOW = 0x0609_0032
    GENERAL = 0x0800_0000
    CANNOT_STORE = 0x0800_0020
    CANNOT_STORE_LOCAL = 0x0800_0021
    CANNOT_STORE_STATE = 0x0800_0022


ABORT_TEXT: dict[AbortCode, str] = {
    AbortCode.TOGGLE_NOT_ALTERNATED: "Toggle bit not alternated",
    AbortCode.SDO_TIMEOUT: "SDO protocol timed out",
    AbortCode.INVALID_COMMAND: "Client/server command specifier not valid or unknown",
    AbortCode.UNSUPPORTED_ACCESS: "Unsupported access to an object",
    AbortCode.WRITE_ONLY: "Attempt to read a write only object",
    AbortCode.READ_ONLY: "Attempt to write a read only object",
    AbortCode.CA_VARIABLE_LENGTH: "SDO complete access not supported for objects of variable "
                                  "length",
    AbortCode.NO_OBJECT: "Object does not exist in the object dictionary",
    AbortCode.HARDWARE_ERROR: "Access failed due to a hardware error",
    AbortCode.NOT_MAPPABLE: "Object cannot be mapped to the PDO",
    AbortCode.PDO_TOO_LONG: "The number and length of the objects to be mapped would exceed "
                            "PDO length",
    AbortCode.TYPE_MISMATCH: "Data type does not match, length of service parameter does not "
                             "match",
    AbortCode.LENGTH_TOO_HIGH: "Data type does not match, length of service parameter too high",
    AbortCode.LENGTH_TOO_LOW: "Data type does not match, length of service parameter too low",
    AbortCode.NO_SUBINDEX: "Sub-index does not exist",
    AbortCode.VALUE_RANGE: "Value range of parameter exceeded",
    AbortCode.VALUE_TOO_HIGH: "Value of parameter written too high",
    AbortCode.VALUE_TOO_LOW: "Value of parameter written too low",
    AbortCode.GENERAL: "General error",
    AbortCode.CANNOT_STORE: "Data cannot be transferred or stored to the application",
    AbortCode.CANNOT_STORE_LOCAL: "Data cannot be transferred or stored to the application "
                                  "because of local control",
    AbortCode.CANNOT_STORE_STATE: "Data cannot be transferred or stored to the application "
                                  "because of the present device state",
}


class SdoAbort(Exception):
    """An object-dictionary access refused with a DS301 abort code."""

    def __init__(self, code: AbortCode, index: int, sub: int) -> None:
        self.code = code
        self.index = index
        self.sub = sub
        super().__init__(f"0x{index:04X}:{sub} -> abort 0x{int(code):08X} "
                         f"({ABORT_TEXT.get(code, code.name)})")


Getter = Callable[[], Any]
Setter = Callable[[Any], None]


@dataclass
class OdEntry:
    index: int
    sub: int
    name: str
    dtype: DataType
    access: Access
    default: Any = 0
    low: int | None = None  # value range beyond the type's own, for writes
    high: int | None = None
    pdo_mappable: bool = False
    getter: Getter | None = None  # live value from the model; None = stored value
    setter: Setter | None = None  # called after checks with the new value
    # The setter only stores what the getter reads back, with no edge or side effect: writing
    # the value the entry holds changes nothing (a model that skips still steps need not be
    # told of it; devices/fastcat/objects.py).
    plain_store: bool = False
    # The value in words where the number alone misleads (0x1003:1 packs an alarm number in
    # hex into its upper word): the Objects tab shows this text instead of the bare number.
    explain: Callable[[Any], str] | None = None
    # Whether the value can be reached now: a FastCAT module's own object lives in the module,
    # which the coupler asks over its internal bus. False: a read or write from outside aborts
    # 0x06060000 (the model and its views still peek / poke the last value).
    reachable: Callable[[], bool] | None = None
    # Which PDO direction a mappable entry goes into: True an input (TxPDO), False an output
    # (RxPDO); None: by its access, rw an output. Said where a writable entry is an input
    # (a FastCAT encoder position 0x6500, preset by SDO, read in the TxPDO).
    pdo_input: bool | None = None

    def check_value(self, value: Any) -> Any:
        if self.dtype is DataType.OCTET_STRING:
            if not isinstance(value, bytes | bytearray):
                raise SdoAbort(AbortCode.TYPE_MISMATCH, self.index, self.sub)
            return bytes(value)
        if self.dtype is DataType.VISIBLE_STRING:
            if not isinstance(value, str):
                raise SdoAbort(AbortCode.TYPE_MISMATCH, self.index, self.sub)
            return value
        if isinstance(value, bool):
            value = int(value)
        if not isinstance(value, int):
            raise SdoAbort(AbortCode.TYPE_MISMATCH, self.index, self.sub)
        _fmt, tmin, tmax = _NUMERIC[self.dtype]
        low = tmin if self.low is None else max(tmin, self.low)
        high = tmax if self.high is None else min(tmax, self.high)
        if value < low:
            raise SdoAbort(AbortCode.VALUE_TOO_LOW, self.index, self.sub)
        if value > high:
            raise SdoAbort(AbortCode.VALUE_TOO_HIGH, self.index, self.sub)
        return value

    @property
    def bit_length(self) -> int:
        if self.dtype is DataType.BOOLEAN:
            return 1
        if self.dtype is DataType.VISIBLE_STRING:
            return 8 * len(str(self.default))
        if self.dtype is DataType.OCTET_STRING:
            return 8 * len(bytes(self.default))
        return 8 * struct.calcsize(_NUMERIC[self.dtype][0])


def encode(dtype: DataType, value: Any) -> bytes:
    if dtype is DataType.OCTET_STRING:
        return bytes(value)
    if dtype is DataType.VISIBLE_STRING:
        return str(value).encode("latin-1")
    return struct.pack(_NUMERIC[dtype][0], int(value))


def decode(dtype: DataType, raw: bytes) -> Any:
    if dtype is DataType.OCTET_STRING:
        return bytes(raw)
    if dtype is DataType.VISIBLE_STRING:
        return raw.decode("latin-1")
    fmt = _NUMERIC[dtype][0]
    if len(raw) != struct.calcsize(fmt):
        code = AbortCode.LENGTH_TOO_HIGH if len(raw) > struct.calcsize(fmt) else \
            AbortCode.LENGTH_TOO_LOW
        raise SdoAbort(code, 0, 0)
    return struct.unpack(fmt, raw)[0]


def download_value(entry: OdEntry, raw: bytes) -> Any:
    """The value an SDO download's bytes carry for ``entry``, checked in a slave's order:
    a read-only object aborts 0x06010002 whatever the length, then a length unlike the
    type's 0x06070012 / 0x06070013; each abort names the object written. The wire's path and
    the built-in master's (devices/esm.py CoeMailbox) both take it, so they answer alike."""
    if not entry.access.writable:
        raise SdoAbort(AbortCode.READ_ONLY, entry.index, entry.sub)
    try:
        return decode(entry.dtype, bytes(raw))
    except SdoAbort as exc:
        raise SdoAbort(exc.code, entry.index, entry.sub) from None


class ObjectDictionary:
    """Entries keyed by (index, sub), with stored values for entries without a getter."""

    def __init__(self) -> None:
        self._entries: dict[tuple[int, int], OdEntry] = {}
        self._values: dict[tuple[int, int], Any] = {}

    def add(self, entry: OdEntry) -> OdEntry:
        key = (entry.index, entry.sub)
        if key in self._entries:
            raise ValueError(f"duplicate object 0x{entry.index:04X}:{entry.sub}")
        self._entries[key] = entry
        self._values[key] = entry.default
        return entry

    def __contains__(self, key: tuple[int, int]) -> bool:
        return key in self._entries

    def __iter__(self) -> Iterator[OdEntry]:
        return iter(sorted(self._entries.values(), key=lambda e: (e.index, e.sub)))

    def __len__(self) -> int:
        return len(self._entries)

    def announce_writes(self, before: Callable[[OdEntry, Any], None],
                        entries: Iterable[OdEntry] | None = None) -> None:
        """Call ``before(entry, value)`` ahead of every value stored into ``entries`` (default:
        every entry with a setter): how a model that skips still steps learns that a write
        from outside its step touched it. Call once, after the last entry was added."""
        chosen = [e for e in self if e.setter is not None] if entries is None else list(entries)
        for entry in chosen:
            def write(value: Any, entry: OdEntry = entry,
                      setter: Callable[[Any], None] | None = entry.setter) -> None:
                before(entry, value)
                if setter is not None:
                    setter(value)
            entry.setter = write

    def has_index(self, index: int) -> bool:
        return any(i == index for i, _ in self._entries)

    def entry(self, index: int, sub: int) -> OdEntry:
        found = self._entries.get((index, sub))
        if found is None:
            code = AbortCode.NO_SUBINDEX if self.has_index(index) else AbortCode.NO_OBJECT
            raise SdoAbort(code, index, sub)
        return found

    def read(self, index: int, sub: int) -> Any:
        entry = self.entry(index, sub)
        if not entry.access.readable:
            raise SdoAbort(AbortCode.WRITE_ONLY, index, sub)
        if entry.reachable is not None and not entry.reachable():
            raise SdoAbort(AbortCode.HARDWARE_ERROR, index, sub)
        return self.peek(index, sub)

    def peek(self, index: int, sub: int) -> Any:
        """The value without access checks (for the model itself and its views)."""
        entry = self.entry(index, sub)
        return entry.getter() if entry.getter is not None else self._values[(index, sub)]

    def write(self, index: int, sub: int, value: Any) -> None:
        """A write from outside (master, SDO client, operator): access and range enforced."""
        entry = self.entry(index, sub)
        if not entry.access.writable:
            raise SdoAbort(AbortCode.READ_ONLY, index, sub)
        if entry.reachable is not None and not entry.reachable():
            raise SdoAbort(AbortCode.HARDWARE_ERROR, index, sub)
        self.poke(index, sub, entry.check_value(value))

    def poke(self, index: int, sub: int, value: Any) -> None:
        """Store a value without access checks (the model updating its own objects)."""
        entry = self.entry(index, sub)
        self._values[(index, sub)] = value
        if entry.setter is not None:
            entry.setter(value)
