"""The coupler's object dictionary, generated from the modules found by the last scan.

Seed 000 §5 (PDO layout) and §6.1-§6.5, §6.16-§6.23, §6.31 (coupler objects); the per-module
objects come from each module's ``add_objects`` at ``base + 0x10 * (n - 1)``. Choices on
ambiguous rows are in docs/fastcat-coupler.md.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any, Protocol

from devices.fastcat.catalog import ModuleType
from devices.fastcat.modules import IoModule
from devices.od import Access, DataType, ObjectDictionary, OdEntry

DEVICE_TYPE = 0x0000_1389  # §6.1: 5001 = MDP (printed "0x000013989 (5001)")
DEVICE_NAME = "FastCAT"  # §6.2
HW_VERSION = "1.0"  # §6.3
SW_VERSION = "1.0"  # §6.4 (index 0x100A; the heading prints 0x1009)
VENDOR_ID = 0xC6  # §6.5
PRODUCT_CODE = 0x0000_FACA  # §6.5
REVISION = 0x0001_0007  # §6.5 prints "-": FieldRig reports firmware FastCAT 1.7 (title page)
MODULE_FW_VERSION = 0x0001_0000  # §6.21 prints "-": FieldRig value for every module
MODULE_HW_REVISION = 0x0000_0001  # §6.22 prints "-": FieldRig value for every module

RXPDO_BASE = 0x1600  # §5: 0x1600 + (n - 1), outputs, SM2
TXPDO_BASE = 0x1A00  # §5: 0x1A00 + (n - 1), inputs, SM3
COUPLER_RXPDO = 0x16FF  # §5: always present, the Reset fault bit
COUPLER_TXPDO = 0x1AFF  # §5: always present, the Fault active bit
COUPLER_PDO_GAP = (0x0000, 0, 7)  # §6.16 / §6.17 "2:8 Reserved (7)"
RXPDO_ASSIGN = 0x1C12
TXPDO_ASSIGN = 0x1C13
MAX_MODULES = 16  # §2
# PDO names as a configurator lists them (§4 "Slave settings": 0x1AFF "Status", a DB16's
# 0x1A00 "Inputs", an AI8D's / AI8C's "Analog inputs"); the rest in the same style, by the
# module's §2 column. Module PDOs: (RxPDO, TxPDO).
COUPLER_PDO_NAMES = ("Control", "Status")
MODULE_PDO_NAMES = {"digital": ("Outputs", "Inputs"),
                    "analog": ("Analog outputs", "Analog inputs"),
                    "encoder": ("Encoder outputs", "Encoder inputs")}


class CouplerObjects(Protocol):
    """The live coupler values behind 0x5100..0x5400 (getters/setters of the entries)."""

    def od_fault_active(self) -> bool: ...
    def od_reset_fault(self) -> int: ...
    def od_set_reset_fault(self, value: int) -> None: ...
    def od_comm_errors(self, n: int) -> int: ...
    def od_address_check(self) -> int: ...
    def od_set_address_check(self, value: int) -> None: ...
    def od_rotary(self) -> int: ...
    def od_emergency_word(self) -> int: ...
    def od_configured(self, sub: int) -> int: ...
    def od_set_configured(self, sub: int, value: int) -> None: ...
    def od_module_answers(self, n: int) -> bool: ...
    SKIP_SAME_WRITES: bool  # False: every write touches the coupler (the plain path, tests)


def pdo_entry(index: int, sub: int, bit_length: int) -> int:
    """A PDO mapping entry: index << 16 | sub << 8 | bit length (ETG.1000.6)."""
    return index << 16 | sub << 8 | bit_length


def build_od(coupler: CouplerObjects, modules: Sequence[IoModule], serial: int,
             on_write: Callable[[bool], None] | None = None) -> ObjectDictionary:
    """``modules``: the detected modules in bus order (module n = ``modules[n - 1]``).
    ``on_write(module)`` is called before every write that reaches the model (an entry's
    setter) and may change it (not for a ``plain_store`` entry written with the value it
    holds); ``module`` says whether the entry is a module's object or the coupler's own."""
    od = ObjectDictionary()
    _identity(od, serial)
    _pdos(od, modules)
    _coupler_objects(od, coupler, len(modules))
    _module_lists(od, modules)
    _configured_list(od, coupler)
    coupler_keys = {(entry.index, entry.sub) for entry in od}
    for n, module in enumerate(modules, start=1):
        module.add_objects(od, n)
    _module_side(od, coupler, coupler_keys)
    if on_write is not None:
        announce = on_write

        def before(entry: OdEntry, value: Any) -> None:
            # A master writes its whole process image every cycle, nearly all of it the values
            # the entries hold: such a write changes nothing, and the coupler's next step may
            # stay a still one (docs/fastcat-coupler.md "Step cost").
            if entry.plain_store and coupler.SKIP_SAME_WRITES and entry.getter is not None \
                    and entry.getter() == value:
                return
            announce((entry.index, entry.sub) not in coupler_keys)
        od.announce_writes(before)
    return od


def _module_side(od: ObjectDictionary, coupler: CouplerObjects,
                 coupler_keys: set[tuple[int, int]]) -> None:
    """A module's settings (§6.6-§6.15: 0x2004 .. 0x4500) live in the module: the coupler
    reads and writes them with SDORX commands on its internal bus (§7.5 0x07 / 0x08, 0x0A -
    0x0E name their answers and timeouts), so a module that does not answer cannot give or take
    one, and a master's access aborts. Its process data (0x6000 .. 0x7600, in the PDOs) is the
    coupler's image, and sub 0's count is the coupler's own layout: both still answer."""
    for entry in od:
        if (entry.index, entry.sub) in coupler_keys or entry.pdo_mappable \
                or entry.getter is None:
            continue
        n = (entry.index >> 4 & 0xF) + 1  # §6: base + 0x10 * (n - 1), every base ends in 0xN0X
        entry.reachable = partial(coupler.od_module_answers, n)


def _ro(od: ObjectDictionary, index: int, sub: int, name: str, dtype: DataType, value: Any,
        **kw: Any) -> None:
    od.add(OdEntry(index, sub, name, dtype, Access.RO, value, **kw))


def _identity(od: ObjectDictionary, serial: int) -> None:
    _ro(od, 0x1000, 0, "Device type", DataType.UNSIGNED32, DEVICE_TYPE)
    _ro(od, 0x1008, 0, "Device name", DataType.VISIBLE_STRING, DEVICE_NAME)
    _ro(od, 0x1009, 0, "Hardware version", DataType.VISIBLE_STRING, HW_VERSION)
    _ro(od, 0x100A, 0, "Software version", DataType.VISIBLE_STRING, SW_VERSION)
    _ro(od, 0x1018, 0, "N° of entries", DataType.UNSIGNED8, 4)
    _ro(od, 0x1018, 1, "Vendor ID", DataType.UNSIGNED32, VENDOR_ID)
    _ro(od, 0x1018, 2, "Product code", DataType.UNSIGNED32, PRODUCT_CODE)
    _ro(od, 0x1018, 3, "Revision num.", DataType.UNSIGNED32, REVISION)
    _ro(od, 0x1018, 4, "Serial number", DataType.UNSIGNED32, serial)


def _mapping(od: ObjectDictionary, index: int, name: str,
             entries: Sequence[tuple[int, int, int]]) -> None:
    # §5: generated by the coupler, "la configurazione della mappatura non può essere
    # modificata": every sub is read-only (a write answers abort 0x06010002).
    _ro(od, index, 0, name, DataType.UNSIGNED8, len(entries))
    for sub, (e_index, e_sub, bits) in enumerate(entries, start=1):
        _ro(od, index, sub, f"{name} entry {sub}", DataType.UNSIGNED32,
            pdo_entry(e_index, e_sub, bits))


def _pdos(od: ObjectDictionary, modules: Sequence[IoModule]) -> None:
    rx_assigned = [COUPLER_RXPDO]
    tx_assigned = [COUPLER_TXPDO]
    # §6.16 / §6.17 print the bit, then "2:8 Reserved (7)": the coupler's PDOs are one byte
    # (a 7-bit gap, ETG.1000.6 index 0), so the modules' entries start byte-aligned.
    _mapping(od, COUPLER_RXPDO, COUPLER_PDO_NAMES[0], [(0x5200, 1, 1), COUPLER_PDO_GAP])
    _mapping(od, COUPLER_TXPDO, COUPLER_PDO_NAMES[1], [(0x5100, 1, 1), COUPLER_PDO_GAP])
    for n, module in enumerate(modules, start=1):
        rx, tx = module_pdos(od, module, n)
        if rx:
            rx_assigned.append(RXPDO_BASE + n - 1)
        if tx:
            tx_assigned.append(TXPDO_BASE + n - 1)
    for index, name, assigned in ((RXPDO_ASSIGN, "RxPDO assign", rx_assigned),
                                  (TXPDO_ASSIGN, "TxPDO assign", tx_assigned)):
        _ro(od, index, 0, name, DataType.UNSIGNED8, len(assigned))
        for sub, pdo in enumerate(assigned, start=1):
            _ro(od, index, sub, f"{name} {sub}", DataType.UNSIGNED16, pdo)


def module_pdos(od: ObjectDictionary, module: IoModule, n: int) -> tuple[bool, bool]:
    """Module ``n``'s mapping objects 0x1600 / 0x1A00 + (n - 1) (§5); whether each maps
    anything (an empty one is not assigned)."""
    rx, tx = module.rx_entries(n), module.tx_entries(n)
    rx_name, tx_name = MODULE_PDO_NAMES[module.mtype.group]
    _mapping(od, RXPDO_BASE + n - 1, rx_name, rx)
    _mapping(od, TXPDO_BASE + n - 1, tx_name, tx)
    return bool(rx), bool(tx)


def catalog_objects(mtype: ModuleType) -> ObjectDictionary:
    """The objects and mapping objects a module of type ``mtype`` brings as module 1, apart
    from any rig: a configurator's catalogue entry (the ESI's Modules), from the code that
    builds the coupler's own dictionary. Values are a fresh module's (no rig options)."""
    module = IoModule(mtype, random.Random(0))  # its values do not matter: only the layout
    od = ObjectDictionary()
    module_pdos(od, module, 1)
    module.add_objects(od, 1)
    return od


def _coupler_objects(od: ObjectDictionary, c: CouplerObjects, count: int) -> None:
    # §6.16 coupler status, mapped in 0x1AFF.
    _ro(od, 0x5100, 0, "N° of entries", DataType.UNSIGNED8, 8)
    _ro(od, 0x5100, 1, "Fault active", DataType.BOOLEAN, False, pdo_mappable=True,
        getter=c.od_fault_active)
    for sub in range(2, 9):
        _ro(od, 0x5100, sub, "Reserved", DataType.BOOLEAN, False)
    # §6.17 coupler control, mapped in 0x16FF.
    _ro(od, 0x5200, 0, "N° of entries", DataType.UNSIGNED8, 8)
    od.add(OdEntry(0x5200, 1, "Reset fault", DataType.BOOLEAN, Access.RW, False,
                   pdo_mappable=True, getter=c.od_reset_fault, setter=c.od_set_reset_fault,
                   plain_store=True))  # a rising edge is a change of the value
    for sub in range(2, 9):
        _ro(od, 0x5200, sub, "Reserved", DataType.BOOLEAN, False)
    # §6.18: one counter per detected module.
    _ro(od, 0x5300, 0, "N° of entries", DataType.UNSIGNED8, count)
    for n in range(1, count + 1):
        _ro(od, 0x5300, n, f"Errors detected on module {n}", DataType.UNSIGNED32, 0,
            getter=lambda n=n: c.od_comm_errors(n))
    # §6.19 prints "ro" but says writing 1 enables the check: rw, 0..1.
    od.add(OdEntry(0x5301, 0, "Enable address checking", DataType.UNSIGNED8, Access.RW, 0,
                   high=1, getter=c.od_address_check, setter=c.od_set_address_check))
    _ro(od, 0x5302, 0, "Physical address detected", DataType.UNSIGNED8, 0, getter=c.od_rotary)
    _ro(od, 0x5400, 0, "Emergency data", DataType.UNSIGNED32, 0,
        getter=c.od_emergency_word)


def _module_lists(od: ObjectDictionary, modules: Sequence[IoModule]) -> None:
    for index, name, value in ((0x5310, "Firmware version of module", MODULE_FW_VERSION),
                               (0x5320, "Hardware revision of module", MODULE_HW_REVISION)):
        _ro(od, index, 0, "N° of entries", DataType.UNSIGNED8, MAX_MODULES)
        for n in range(1, MAX_MODULES + 1):
            _ro(od, index, n, f"{name} {n}", DataType.UNSIGNED32,
                value if n <= len(modules) else 0)
    # §6.31: product code of the module detected at each bus position.
    _ro(od, 0xF050, 0, "N° of entries", DataType.UNSIGNED8, len(modules))
    for n, module in enumerate(modules, start=1):
        _ro(od, 0xF050, n, f"Module detected in position {n}", DataType.UNSIGNED32,
            module.mtype.product_code)


def _configured_list(od: ObjectDictionary, c: CouplerObjects) -> None:
    # ETG.5001 0xF030, named by §7.5 0x14 / §7.7 0x0070: the master's configured modules,
    # written in PRE-OP (the setter refuses other states, and RW_PREOP says so to the Objects
    # tab and to SDO information); sub 0 = how many entries count.
    od.add(OdEntry(0xF030, 0, "N° of entries", DataType.UNSIGNED8, Access.RW_PREOP, 0,
                   high=MAX_MODULES, getter=lambda: c.od_configured(0),
                   setter=lambda v: c.od_set_configured(0, v)))
    for n in range(1, MAX_MODULES + 1):
        od.add(OdEntry(0xF030, n, f"Module configured in position {n}", DataType.UNSIGNED32,
                       Access.RW_PREOP, 0, getter=lambda n=n: c.od_configured(n),
                       setter=lambda v, n=n: c.od_set_configured(n, v)))
