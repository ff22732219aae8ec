"""The CPX-E-EC's object dictionary (seed 002 §3, Tab. 27 "Каталог объектов (Modular Device
Profile)"), rebuilt at every start from the modules the bus module found.

Module xx is the CPX module number (0 = the bus module with status bits or the I/O diagnostic
interface, 1 ... 10 the I/O modules); MDP slot = xx + 1 in 0xF030 / 0xF050. Values the seed
leaves blank, and the objects added beyond Tab. 27 (0x1002 named by Tab. 20, 0xF030 named by
Text-ID 0x3801), are listed in docs/cpx-e-ec.md.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

from devices.cpx.assignment import RX_ASSIGN, TX_ASSIGN, address_order
from devices.cpx.catalog import ModuleType
from devices.cpx.codes import ERROR_REGISTER_WORDS
from devices.cpx.history import FIRST_SUB, FLAG_WORDS, INDEX, MAX_MESSAGES, DiagHistory
from devices.cpx.messages import MESSAGE_BYTES
from devices.cpx.modules import ANALOG_RANGES, CpxModule
from devices.od import (
    AbortCode,
    Access,
    DataType,
    ObjectDictionary,
    OdEntry,
    SdoAbort,
    TypeNames,
)
from devices.pdo_assign import PdoAssignment

DEVICE_TYPE = 0x0456_1389  # Tab. 27 (0x1389 = 5001, MDP)
DEVICE_NAME = "CPX-E-EC"  # Tab. 27
HW_VERSION = "1"  # Tab. 2: product version 1 onwards; Tab. 27 prints no value
SW_VERSION = "1.0"  # FieldRig (Tab. 27 prints no value)
VENDOR_ID = 0x0000_001D  # Tab. 27
PRODUCT_CODE = 0x0029_BF59  # FieldRig (Tab. 27 prints no value)
REVISION = 0x0000_0001  # Tab. 2: version 1
LOCAL_ERROR_REACTION = 0  # 0x10F1:1, no value printed
SYNC_ERROR_COUNTER_LIMIT = 4  # 0x10F1:2, no value printed: ETG.1020's usual 4
INDEX_DISTANCE = 1  # 0xF000:1
MAX_MODULES_MDP = 48  # 0xF000:2, 0xF050 subs 1 ... 48
DIAG_PDO = 0x1A40
NEW_MESSAGE_MAPPING = 0x10F3_0401  # Tab. 27 prints "0x10F3:00,1": read as 0x10F3:04, 1 bit
BUILD_HASH = "f1e1d2a9"  # 0x5001, FieldRig
FAILSAFE_MODES = (0, 1, 2)  # 0x2400:7: reset outputs / hold last state / failsafe values

# Tab. 14 / Tab. 27's data types: U8, U16, U32, BOOL, STRING, "BYTE[23]" for a 0x10F3 message
# and "ARRAY OF BYTE" for a byte array of no fixed size (0x22xx:7). The seed prints no signed
# type; the analog channels (INTEGER16) follow its U8 / U16 pattern (docs/cpx-e-ec.md 42).
TYPE_NAMES = TypeNames({
    DataType.BOOLEAN: "BOOL", DataType.INTEGER8: "I8", DataType.INTEGER16: "I16",
    DataType.INTEGER32: "I32", DataType.UNSIGNED8: "U8", DataType.UNSIGNED16: "U16",
    DataType.UNSIGNED32: "U32", DataType.VISIBLE_STRING: "STRING",
    DataType.OCTET_STRING: "ARRAY OF BYTE"}, sized_octets="BYTE[{size}]")


class CpxObjects(Protocol):
    """What the dictionary reads live from the bus module (devices/cpx/device.py)."""

    serial: int
    units: list[CpxModule]  # module 0 (the bus module) first
    history: DiagHistory
    tx_assign: PdoAssignment

    def od_error_register(self) -> int: ...
    def od_status_register(self) -> int: ...
    def od_history_message(self, sub: int) -> bytes: ...
    def od_f030_written(self, value: Any) -> None: ...
    def od_unique_id(self) -> str: ...


def pdo_entry(index: int, sub: int, bits: int) -> int:
    """A mapping entry: index << 16 | sub << 8 | bit length ("0x60xx:yy,s", Tab. 27)."""
    return index << 16 | sub << 8 | bits


def _ro(od: ObjectDictionary, index: int, sub: int, name: str, dtype: DataType, value: Any,
        **kw: Any) -> None:
    od.add(OdEntry(index, sub, name, dtype, Access.RO, value, **kw))


def build_od(dev: CpxObjects) -> ObjectDictionary:
    od = ObjectDictionary()
    _identity(od, dev)
    _history(od, dev)
    for unit in dev.units:
        if unit.mtype.inputs or unit.mtype.outputs:
            _module_pdos(od, unit)
        _module_parameters(od, unit)
    _ro(od, DIAG_PDO, 0, "Diag History – TxPDO", DataType.UNSIGNED8, 1)
    _fixed(od, DIAG_PDO, 1, "Input Mapping 01", NEW_MESSAGE_MAPPING)
    _assignment(od, dev)
    _global_settings(od)
    _terminal_info(od, dev)
    _module_lists(od, dev)
    return od


def _identity(od: ObjectDictionary, dev: CpxObjects) -> None:
    _ro(od, 0x1000, 0, "Device Type", DataType.UNSIGNED32, DEVICE_TYPE)
    _ro(od, 0x1001, 0, "Error Register", DataType.UNSIGNED8, 0, getter=dev.od_error_register,
        explain=ERROR_REGISTER_WORDS.said)  # Tab. 22's names of the set bits
    # Tab. 20 names index 1002 (Manufacturer Status Register) as the source of byte 3.
    _ro(od, 0x1002, 0, "Manufacturer Status Register", DataType.UNSIGNED32, 0,
        getter=dev.od_status_register)
    _ro(od, 0x1008, 0, "Device Name", DataType.VISIBLE_STRING, DEVICE_NAME)
    _ro(od, 0x1009, 0, "Hardware Version", DataType.VISIBLE_STRING, HW_VERSION)
    _ro(od, 0x100A, 0, "Software Version", DataType.VISIBLE_STRING, SW_VERSION)
    for sub, name, value in ((0, "Identify", 4), (1, "Vendor ID", VENDOR_ID),
                             (2, "Product Code", PRODUCT_CODE), (3, "Revision", REVISION),
                             (4, "Serial Number", dev.serial)):
        _ro(od, 0x1018, sub, name, DataType.UNSIGNED8 if sub == 0 else DataType.UNSIGNED32,
            value)
    _ro(od, 0x10F1, 0, "Error Settings", DataType.UNSIGNED8, 2)
    _ro(od, 0x10F1, 1, "Local Error Reaction", DataType.UNSIGNED32, LOCAL_ERROR_REACTION)
    _ro(od, 0x10F1, 2, "Sync Error Counter Limit", DataType.UNSIGNED32,
        SYNC_ERROR_COUNTER_LIMIT)


def _history(od: ObjectDictionary, dev: CpxObjects) -> None:
    h = dev.history
    _ro(od, INDEX, 0, "Diagnosis History", DataType.UNSIGNED8, 0, getter=lambda: h.sub0)
    _ro(od, INDEX, 1, "Maximum Messages", DataType.UNSIGNED8, MAX_MESSAGES)
    _ro(od, INDEX, 2, "Newest Message", DataType.UNSIGNED8, 0, getter=lambda: h.newest)
    od.add(OdEntry(INDEX, 3, "Newest Acknowledged Message", DataType.UNSIGNED8, Access.RW, 0,
                   getter=lambda: h.acknowledged, setter=h.write_acknowledged))
    _ro(od, INDEX, 4, "New Message Available", DataType.BOOLEAN, False, pdo_mappable=True,
        getter=lambda: h.new_message)
    od.add(OdEntry(INDEX, 5, "Flags", DataType.UNSIGNED16, Access.RW, 0x0000,
                   getter=lambda: h.flags, setter=h.write_flags,
                   explain=FLAG_WORDS.said))  # Tab. 18 / 19
    for sub in range(FIRST_SUB, FIRST_SUB + MAX_MESSAGES):
        # BYTE[23] (Tab. 14 / 27): the default gives the entry its 23-byte size (the SDO
        # information service reports it); the value is the stored message's bytes.
        _ro(od, INDEX, sub, f"Subindex {sub:03d}", DataType.OCTET_STRING,
            bytes(MESSAGE_BYTES), getter=lambda sub=sub: dev.od_history_message(sub))


def _assignment(od: ObjectDictionary, dev: CpxObjects) -> None:
    """0x1C12 read-only, 0x1C13 written in PREOP (devices/cpx/assignment.py); beyond Tab. 27
    (docs/cpx-e-ec.md choice 13)."""
    rx = address_order(dev.units, receive=True)
    _ro(od, RX_ASSIGN, 0, "RxPDO assign", DataType.UNSIGNED8, len(rx))
    for sub, pdo in enumerate(rx, start=1):
        _ro(od, RX_ASSIGN, sub, f"RxPDO assign {sub}", DataType.UNSIGNED16, pdo)
    tx = dev.tx_assign
    od.add(OdEntry(TX_ASSIGN, 0, "TxPDO assign", DataType.UNSIGNED8, Access.RW_PREOP, tx.count,
                   getter=lambda: tx.count, setter=tx.set_count))
    for sub in range(1, len(tx.entries) + 1):
        od.add(OdEntry(TX_ASSIGN, sub, f"TxPDO assign {sub}", DataType.UNSIGNED16,
                       Access.RW_PREOP, 0, getter=lambda sub=sub: tx.entries[sub - 1],
                       setter=lambda value, sub=sub: tx.set_entry(sub, value)))


def _fixed(od: ObjectDictionary, index: int, sub: int, name: str, value: int) -> None:
    """A RW mapping entry of a fixed-layout module: only its own value is accepted."""
    def check(written: Any) -> None:
        if written != value:
            raise SdoAbort(AbortCode.VALUE_RANGE, index, sub)
    od.add(OdEntry(index, sub, name, DataType.UNSIGNED32, Access.RW, value,
                   getter=lambda: value, setter=check))


def _module_pdos(od: ObjectDictionary, unit: CpxModule) -> None:
    xx = unit.number
    for base, pdo_base, entries, direction in (
            (0x6000, 0x1A00, unit.mtype.inputs, "Input"),
            (0x7000, 0x1600, unit.mtype.outputs, "Output")):
        if not entries:
            continue
        index, pdo = base + xx, pdo_base + xx
        _ro(od, index, 0, f"Module {direction}s", DataType.UNSIGNED8, len(entries))
        for sub, entry in enumerate(entries, start=1):
            # the module replaces its image lists: read them through the module every time
            if direction == "Output":
                od.add(OdEntry(index, sub, entry.name, entry.dtype, Access.RW, 0,
                               pdo_mappable=True,
                               getter=lambda i=sub - 1: unit.out_values[i],
                               setter=lambda value, i=sub - 1: _set_output(unit, i, value)))
            else:
                _ro(od, index, sub, entry.name, entry.dtype, 0, pdo_mappable=True,
                    getter=lambda i=sub - 1: unit.in_values[i])
        mapped = [pdo_entry(index, sub, e.bits) for sub, e in enumerate(entries, start=1)]
        if direction == "Input" and unit.mtype.input_pad_bits:
            mapped.append(unit.mtype.input_pad_bits)  # a gap: index 0, sub 0, n bits
        side = "TxPDO" if direction == "Input" else "RxPDO"
        _ro(od, pdo, 0, f"Module {xx} – {side}", DataType.UNSIGNED8, len(mapped))
        for sub, value in enumerate(mapped, start=1):
            _fixed(od, pdo, sub, f"{direction} Mapping {sub:02d}", value)


def _set_output(unit: CpxModule, channel: int, value: Any) -> None:
    unit.out_values[channel] = int(value)


def _module_parameters(od: ObjectDictionary, unit: CpxModule) -> None:
    xx, mtype = unit.number, unit.mtype
    if mtype.analog_ranges:  # 0x20xx: one signal range per channel
        _ro(od, 0x2000 + xx, 0, f"Module Parameter – Module {xx}", DataType.UNSIGNED8,
            mtype.channels)
        for ch in range(mtype.channels):
            od.add(OdEntry(0x2000 + xx, ch + 1, f"Signal range channel {ch}",
                           DataType.UNSIGNED8, Access.RW, unit.ranges[ch],
                           getter=lambda ch=ch: unit.ranges[ch],
                           setter=_range_setter(unit, ch)))
    if mtype.outputs and not _is_bus(mtype):  # 0x21xx: failsafe value per output channel
        _ro(od, 0x2100 + xx, 0, f"Failsafe Values – Module {xx}", DataType.UNSIGNED8,
            len(mtype.outputs))
        for ch, entry in enumerate(mtype.outputs):
            od.add(OdEntry(0x2100 + xx, ch + 1, f"Channel {ch}", entry.dtype, Access.RW, 0,
                           getter=lambda ch=ch: unit.failsafe[ch],
                           setter=lambda v, ch=ch: _set_failsafe(unit, ch, v)))


def _set_failsafe(unit: CpxModule, channel: int, value: Any) -> None:
    unit.failsafe[channel] = int(value)


def _is_bus(mtype: ModuleType) -> bool:
    return mtype.name == DEVICE_NAME


def _range_setter(unit: CpxModule, ch: int) -> Callable[[Any], None]:
    def write(value: Any) -> None:
        if value not in ANALOG_RANGES:
            raise SdoAbort(AbortCode.VALUE_RANGE, 0x2000 + unit.number, ch + 1)
        unit.ranges[ch] = int(value)
    return write


def _global_settings(od: ObjectDictionary) -> None:
    _ro(od, 0x2400, 0, "Global CPX Settings", DataType.UNSIGNED8, 8)
    rows: Sequence[tuple[int, str, DataType, Any]] = (
        (1, "Filter Alarm V_OUT/V_SEN", DataType.UNSIGNED8, 0x00),
        (2, "Monitor SCS", DataType.BOOLEAN, True),
        (3, "Monitor SCO", DataType.BOOLEAN, True),
        (4, "Monitor V_OUT", DataType.BOOLEAN, True),
        (5, "Monitor V_VEN", DataType.BOOLEAN, True),  # VEN: Ventile, the valves' supply
        (6, "Monitor SCV", DataType.BOOLEAN, True),
        (7, "Fail safe", DataType.UNSIGNED8, 0x00),
        (8, "System Start", DataType.UNSIGNED8, 0x00))
    for sub, name, dtype, default in rows:
        high = max(FAILSAFE_MODES) if sub == 7 else None
        od.add(OdEntry(0x2400, sub, name, dtype, Access.RW, default, high=high))
    od.add(OdEntry(0x2401, 0, "Diagnosis History – Filter No Error", DataType.UNSIGNED8,
                   Access.RW, 0))


def _terminal_info(od: ObjectDictionary, dev: CpxObjects) -> None:
    units = dev.units
    _ro(od, 0x5000, 0, "Generic Terminal Information", DataType.UNSIGNED8, 3)
    _ro(od, 0x5000, 1, "Modules Count", DataType.UNSIGNED8, len(units))
    _ro(od, 0x5000, 2, "Input Length", DataType.UNSIGNED8,
        sum(u.mtype.input_bytes for u in units))
    _ro(od, 0x5000, 3, "Output Length", DataType.UNSIGNED8,
        sum(u.mtype.output_bytes for u in units))
    _ro(od, 0x5001, 0, "Build Hash", DataType.VISIBLE_STRING, BUILD_HASH)
    _ro(od, 0x5002, 0, "Unique ID", DataType.VISIBLE_STRING, dev.od_unique_id())


def _module_lists(od: ObjectDictionary, dev: CpxObjects) -> None:
    _ro(od, 0xF000, 0, "Modular Device Profile", DataType.UNSIGNED8, 2)
    _ro(od, 0xF000, 1, "Index Distance", DataType.UNSIGNED8, INDEX_DISTANCE)
    _ro(od, 0xF000, 2, "Maximum Number Of Modules", DataType.UNSIGNED16, MAX_MODULES_MDP)
    # 0xF030 is not in Tab. 27, but Text-ID 0x3801 says the PLC writes it: the configured
    # list, compared with 0xF050 at PREOP -> SAFEOP. Sub 0 typed like 0xF050's (U16).
    od.add(OdEntry(0xF030, 0, "Configured Module List", DataType.UNSIGNED16, Access.RW, 0,
                   high=MAX_MODULES_MDP, setter=dev.od_f030_written))
    for sub in range(1, MAX_MODULES_MDP + 1):
        od.add(OdEntry(0xF030, sub, f"Subindex {sub:03d}", DataType.UNSIGNED32, Access.RW, 0,
                       setter=dev.od_f030_written))
    _ro(od, 0xF050, 0, "Detected Module List", DataType.UNSIGNED16, len(dev.units))
    for sub in range(1, MAX_MODULES_MDP + 1):
        ident = dev.units[sub - 1].mtype.ident if sub <= len(dev.units) else 0
        _ro(od, 0xF050, sub, f"Subindex {sub:03d}", DataType.UNSIGNED32, ident)
