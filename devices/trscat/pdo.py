"""Process data of the TRS-CAT: the per-slot objects, PDO mappings and the SM assignments.

Seed 001 §9.3.3 (Modular Device Profile, ETG.5001: one RxPDO and one TxPDO per module; the
integrated module is RxPDO 0x1600 -> 0x7000, 16 outputs, and TxPDO 0x1A00 -> 0x6000, 16
inputs; the extra TxPDO 0x1AFF is 0xF100), §9.3.4 (0x1AFF = 0xF100 1:1 plus sub 5, the "New
message available" of 0x10F3:4) and §9.3.2 (0x1C12 / 0x1C13 are read-only and follow the
slot configuration written to 0xF030). Slot s uses 0x6000 / 0x7000 + 0x10 * s and
0x1600 / 0x1A00 + s (the MDP index distance, 0xF000:1 = 0x10).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from devices.od import Access, DataType, ObjectDictionary, OdEntry
from devices.trscat.catalog import IoShape, ModuleKind

INPUTS_BASE = 0x6000
OUTPUTS_BASE = 0x7000
RXPDO_BASE = 0x1600
TXPDO_BASE = 0x1A00
DEVICE_TXPDO = 0x1AFF  # §9.3.3 / §9.3.4
RXPDO_ASSIGN = 0x1C12
TXPDO_ASSIGN = 0x1C13
INDEX_DISTANCE = 0x10  # ETG.5001, 0xF000:1

# §9.3.4: 0x1AFF maps 0xF100 subs 1..4 one to one, then 0x10F3:4 as sub 5.
DEVICE_TXPDO_ENTRIES: tuple[tuple[int, int, int], ...] = (
    (0xF100, 1, 8), (0xF100, 2, 1), (0xF100, 3, 1), (0xF100, 4, 1), (0x10F3, 4, 1))

_BITS = {DataType.BOOLEAN: 1, DataType.INTEGER16: 16, DataType.UNSIGNED16: 16}
_CHANNEL = {IoShape.DIGITAL: "I/O {}", IoShape.ANALOG: "Channel {}", IoShape.WORDS: "Word {}"}


def inputs_index(slot: int) -> int:
    return INPUTS_BASE + INDEX_DISTANCE * slot


def outputs_index(slot: int) -> int:
    return OUTPUTS_BASE + INDEX_DISTANCE * slot


def pdo_entry(index: int, sub: int, bits: int) -> int:
    """A PDO mapping entry: index << 16 | sub << 8 | bit length (ETG.1000.6)."""
    return index << 16 | sub << 8 | bits


def rx_entries(slot: int, kind: ModuleKind) -> list[tuple[int, int, int]]:
    bits = _BITS[kind.output_type]
    return [(outputs_index(slot), ch, bits) for ch in range(1, kind.outputs + 1)]


def tx_entries(slot: int, kind: ModuleKind) -> list[tuple[int, int, int]]:
    bits = _BITS[kind.input_type]
    return [(inputs_index(slot), ch, bits) for ch in range(1, kind.inputs + 1)]


def _ro(od: ObjectDictionary, index: int, sub: int, name: str, dtype: DataType,
        value: Any) -> None:
    od.add(OdEntry(index, sub, name, dtype, Access.RO, value))


def _mapping(od: ObjectDictionary, index: int, name: str,
             entries: Sequence[tuple[int, int, int]]) -> None:
    # §9.3.3: the TRS-CAT maps its PDOs itself; the master downloads nothing: read-only.
    _ro(od, index, 0, name, DataType.UNSIGNED8, len(entries))
    for sub, entry in enumerate(entries, start=1):
        _ro(od, index, sub, f"{name} entry {sub}", DataType.UNSIGNED32, pdo_entry(*entry))


def module_mappings(od: ObjectDictionary, slot: int, kind: ModuleKind,
                    names: tuple[str, str]) -> tuple[bool, bool]:
    """Slot ``slot``'s mapping objects 0x1600 / 0x1A00 + slot (§9.3.3), named ``names``
    (outputs, inputs); whether each maps anything (an empty one is not assigned)."""
    rx, tx = rx_entries(slot, kind), tx_entries(slot, kind)
    if rx:
        _mapping(od, RXPDO_BASE + slot, names[0], rx)
    if tx:
        _mapping(od, TXPDO_BASE + slot, names[1], tx)
    return bool(rx), bool(tx)


def add_pdo_mappings(od: ObjectDictionary, configured: Sequence[ModuleKind | None]) -> None:
    """0x16ss / 0x1Ass, 0x1AFF and the assignments 0x1C12 / 0x1C13 for the slots of 0xF030
    (``None``: a slot 0xF030 leaves empty, which gets no PDO). 0x1AFF, the device's own, is
    assigned first and the slots' after it, the order a configurator builds a modular
    device's image in from its ESI (docs/trscat.md "ESI: slots and modules")."""
    rx_assigned: list[int] = []
    tx_assigned: list[int] = [DEVICE_TXPDO]
    for slot, kind in enumerate(configured):
        if kind is None:
            continue
        rx, tx = module_mappings(od, slot, kind, (f"Slot {slot} outputs", f"Slot {slot} inputs"))
        if rx:
            rx_assigned.append(RXPDO_BASE + slot)
        if tx:
            tx_assigned.append(TXPDO_BASE + slot)
    _mapping(od, DEVICE_TXPDO, "Device status", DEVICE_TXPDO_ENTRIES)
    for index, name, assigned in ((RXPDO_ASSIGN, "RxPDO assign", rx_assigned),
                                  (TXPDO_ASSIGN, "TxPDO assign", tx_assigned)):
        _ro(od, index, 0, name, DataType.UNSIGNED8, len(assigned))
        for sub, pdo in enumerate(assigned, start=1):
            _ro(od, index, sub, f"{name} {sub}", DataType.UNSIGNED16, pdo)


def catalog_objects(kind: ModuleKind) -> ObjectDictionary:
    """The objects and mapping objects a module of ``kind`` brings in the first slot (slot 0),
    apart from any device: a configurator's catalogue entry (the ESI's Modules), from the
    code that builds the TRS-CAT's own dictionary. Its PDOs are named after the module (the
    configurator shows them under whichever slot holds it); values do not matter."""
    od = ObjectDictionary()
    module_mappings(od, 0, kind, (f"{kind.name} outputs", f"{kind.name} inputs"))
    add_slot_objects(od, 0, kind, lambda slot, ch: 0, lambda slot, ch: 0,
                     lambda slot, ch, value: None)
    return od


SlotGetter = Callable[[int, int], int]  # (slot, channel 0-based) -> value
SlotSetter = Callable[[int, int, int], None]  # (slot, channel 0-based, value)


def add_slot_objects(od: ObjectDictionary, slot: int, kind: ModuleKind, get_in: SlotGetter,
                     get_out: SlotGetter, put_out: SlotSetter) -> None:
    """0x6ss0 (inputs, RO) and 0x7ss0 (outputs, RW: the image the master writes)."""
    label = _CHANNEL[kind.shape]
    i_index, o_index = inputs_index(slot), outputs_index(slot)
    _ro(od, i_index, 0, "N° of entries", DataType.UNSIGNED8, kind.inputs)
    for ch in range(kind.inputs):
        od.add(OdEntry(i_index, ch + 1, "Input " + label.format(ch + 1), kind.input_type,
                       Access.RO, 0, pdo_mappable=True,
                       getter=lambda ch=ch: get_in(slot, ch)))
    if not kind.outputs:
        return
    _ro(od, o_index, 0, "N° of entries", DataType.UNSIGNED8, kind.outputs)
    for ch in range(kind.outputs):
        od.add(OdEntry(o_index, ch + 1, "Output " + label.format(ch + 1), kind.output_type,
                       Access.RW, 0, pdo_mappable=True,
                       getter=lambda ch=ch: get_out(slot, ch),
                       setter=lambda value, ch=ch: put_out(slot, ch, int(value))))
