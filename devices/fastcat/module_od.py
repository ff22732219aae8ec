"""The per-module objects of seed 000 §6 as data, and how a module adds them to the OD.

Every per-module object lives at ``base + 0x10 * (N - 1)`` for module N = 1..16 (§6.6-§6.30).
``seed_access`` is the attribute §6 prints; ``access`` is what FieldRig enforces. They differ
only for the configuration objects that §6 prints "ro" while §3/§4 say the master writes them
in its Startup list (0x2004, 0x200A, 0x200B, 0x2106): see docs/fastcat-modules.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from devices.od import Access, DataType, ObjectDictionary, OdEntry

MAX_MODULES = 16  # §2
MODULE_STRIDE = 0x10  # §6: index of module N = base + 0x10 * (N - 1)


def object_index(base: int, n: int) -> int:
    if not 1 <= n <= MAX_MODULES:
        raise ValueError(f"module number {n} outside 1..{MAX_MODULES}")
    return base + MODULE_STRIDE * (n - 1)


@dataclass(frozen=True)
class ObjectSpec:
    base: int
    name: str  # the §6 heading
    entry_name: str  # name of sub k (k = 1..), "{}" = k; single objects: the sub-0 name
    dtype: DataType
    access: Access  # enforced
    seed_access: Access  # as §6 prints it
    default: int
    section: str
    low: int | None = None
    high: int | None = None
    pdo: bool = False  # mapped in the module's RxPDO / TxPDO (§5)
    single: bool = False  # the value is sub 0 itself (no "N° of entries")
    pdo_entry: str = ""  # the entry's name in the PDOs (ESI / SII); "" = ``entry_name``


RO, RW = Access.RO, Access.RW
U8, U16, I16, I32, BOOL = (DataType.UNSIGNED8, DataType.UNSIGNED16, DataType.INTEGER16,
                           DataType.INTEGER32, DataType.BOOLEAN)

# fmt: off
OBJECTS: dict[int, ObjectSpec] = {s.base: s for s in (
    ObjectSpec(0x2004, "Channels group configuration", "Channels group config {}", BOOL, RW, RO,
               0, "6.6"),
    ObjectSpec(0x200A, "Analog output ramp", "Analog output {} ramp", U16, RW, RO, 0, "6.7"),
    ObjectSpec(0x200B, "Thermocouple type", "Thermocouple type {}", U8, RW, RO, 0, "6.8",
               low=0, high=1),
    ObjectSpec(0x2104, "Analog inputs filter", "Analog input filter", U16, RW, RW, 4000, "6.9",
               low=1, high=10000, single=True),
    ObjectSpec(0x2106, "Single analog input filter", "Analog input filter {}", U16, RW, RO, 4000,
               "6.10", low=1, high=10000),
    ObjectSpec(0x4000, "Encoders pulses", "Encoder pulses {}", U16, RW, RW, 2048, "6.11", low=1),
    ObjectSpec(0x4001, "Encoders home offset", "Home offset {}", I32, RW, RW, 0, "6.12"),
    ObjectSpec(0x4002, "Encoders disable alarm cnt", "Disable alarm cnt {}", BOOL, RW, RW, 0,
               "6.13"),
    ObjectSpec(0x4003, "Disable encoders", "Disable enc {}", BOOL, RW, RW, 0, "6.14"),
    ObjectSpec(0x4500, "Analog input type", "Type of analog input {}", U8, RW, RW, 4, "6.15",
               low=1, high=5),
    ObjectSpec(0x6000, "Digital inputs", "Digital input {}", BOOL, RO, RO, 0, "6.24", pdo=True,
               pdo_entry="Digital inp {}"),
    ObjectSpec(0x6400, "Analog inputs", "Analog input {}", I16, RO, RO, 0, "6.25", pdo=True,
               pdo_entry="Analog inp {}"),  # §4's screen
    ObjectSpec(0x6500, "Encoders position", "Position encoder {}", I32, RW, RW, 0, "6.26",
               pdo=True),
    ObjectSpec(0x6600, "Encoders operating status", "Operating status", U16, RO, RO, 0, "6.27",
               pdo=True, single=True),
    ObjectSpec(0x7000, "Digital outputs", "Digital output {}", BOOL, RW, RW, 0, "6.28", pdo=True,
               pdo_entry="Digital out {}"),
    ObjectSpec(0x7400, "Analog outputs", "Analog output {}", I16, RW, RW, 0, "6.29", pdo=True,
               pdo_entry="Analog out {}"),
    ObjectSpec(0x7600, "Encoders operating parameters", "Operating parameters", U16, RW, RW, 0,
               "6.30", pdo=True, single=True),
)}
# fmt: on

ChannelGetter = Callable[[int], Any]  # channel (0-based) -> live value
ChannelSetter = Callable[[int, Any], None]  # channel (0-based), checked new value


def add_object(od: ObjectDictionary, base: int, n: int, count: int, get: ChannelGetter,
               put: ChannelSetter | None = None, default: int | None = None,
               plain_store: bool = False) -> int:
    """Add object ``base`` of module ``n`` with ``count`` channels (ignored for single objects).

    Values are live: reads call ``get(channel)``, accepted writes call ``put(channel, value)``;
    ``plain_store``: ``put`` only stores what ``get`` reads back (``OdEntry.plain_store``).
    Returns the object index.
    """
    spec = OBJECTS[base]
    index = object_index(base, n)
    value_default = spec.default if default is None else default

    # §6.24-§6.27: 0x6xxx are "mappati ... nei dati di processo TxPDO", 0x6500 rw included;
    # §6.28-§6.30: 0x7xxx in the RxPDO.
    pdo_input = (spec.base & 0xF000) == 0x6000 if spec.pdo else None

    def entry(sub: int, name: str, channel: int) -> OdEntry:
        return OdEntry(index, sub, name, spec.dtype, spec.access, value_default, spec.low,
                       spec.high, spec.pdo, getter=partial(get, channel),
                       setter=None if put is None else partial(put, channel),
                       plain_store=plain_store, pdo_input=pdo_input)

    if spec.single:
        od.add(entry(0, spec.entry_name, 0))
        return index
    # Sub 0 holds the channel count: §6 prints 0 for 0x6000/0x6400/0x7000/0x7400 and 2 for
    # 0x4500 where the module has more channels; a master needs the real count (docs).
    od.add(OdEntry(index, 0, "N° of entries", DataType.UNSIGNED8, Access.RO, count))
    for ch in range(count):
        od.add(entry(ch + 1, spec.entry_name.format(ch + 1), ch))
    return index


def pdo_entry_name(index: int, sub: int, name: str) -> str:
    """The name of mapped entry ``index:sub`` in the PDOs, its object's sub being ``name``:
    §4's screen lists 0x6420:1 as "Analog inp 1" where §6.25 names the sub "Analog input 1";
    the other channel objects follow that style (docs/fastcat-coupler.md)."""
    spec = OBJECTS.get(index & ~(MODULE_STRIDE * 0xF))
    if spec is None or not spec.pdo_entry or spec.single:
        return name
    return spec.pdo_entry.format(sub)


def pdo_entries(base: int, n: int, count: int) -> list[tuple[int, int, int]]:
    """(index, sub, bit length) of the channels of object ``base`` as mapped in a PDO (§5)."""
    spec = OBJECTS[base]
    bits = OdEntry(0, 0, "", spec.dtype, spec.access).bit_length
    index = object_index(base, n)
    if spec.single:
        return [(index, 0, bits)]
    return [(index, ch + 1, bits) for ch in range(count)]
