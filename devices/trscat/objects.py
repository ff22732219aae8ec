"""The TRS-CAT object dictionary (seed 001 §9.3), a view over the device's state.

Every value lives in the model; entries read it through getters and write it through setters,
so the dictionary can be rebuilt at any time (at the end of the power-up detection and when
0xF030 changes the PDO assignment, §9.3.2). Types and access are the seed's tables; objects the
seed mentions without a table (identity, 0x1001, 0xF000) are the DS301 / ETG.5001 ones with
FieldRig values (docs/trscat.md). "R-WPS" (0xF030, ``Access.RW_PREOP``) is read always,
written in PRE-OP only (its setter refuses the other states).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

from devices.canopen.emcy import REGISTER_WORDS
from devices.od import (
    AbortCode,
    Access,
    DataType,
    ObjectDictionary,
    OdEntry,
    SdoAbort,
    TypeNames,
)
from devices.trscat.catalog import MAX_SLOTS, ModuleKind
from devices.trscat.diagnostics import (
    FIRST_MESSAGE_SUB,
    FLAG_WORDS,
    LAST_MESSAGE_SUB,
    MAX_MESSAGES,
    DiagHistory,
)
from devices.trscat.pdo import add_pdo_mappings, add_slot_objects
from devices.trscat.sync import (
    CALC_COPY_NS,
    DELAY_NS,
    MIN_CYCLE_NS,
    SYNC_ERROR_LIMIT,
    SYNC_MODES_SUPPORTED,
    SyncUnit,
)

DEVICE_TYPE = 0x0000_1389  # DS301 0x1000: profile 5001, the Modular Device Profile (§9.3)
DEVICE_NAME = "TRS-CAT"
HW_VERSION = "01.00"  # §9.3.5: revision 01.00 ...
SW_VERSION = "01.20"  # ... with firmware 01.20, the first with 0xF700 / 0xF701 / 0xF710
VENDOR_ID = 0x0000_0F1E  # FieldRig placeholder: the seed's ESI (TPA_TRSCAT.xml) is not given
PRODUCT_CODE = 0x5452_5343  # FieldRig: "TRSC" in ASCII, like the module idents of §9.3.2
REVISION = 0x0001_0000  # revision 01.00

U8, U16, U32, BOOL = (DataType.UNSIGNED8, DataType.UNSIGNED16, DataType.UNSIGNED32,
                      DataType.BOOLEAN)
RO, RW, RW_PREOP = Access.RO, Access.RW, Access.RW_PREOP

# §9.3's Tipo column: U8, U16, U32, Bool. The seed prints no signed, string or byte-array type;
# FieldRig names those in the same pattern (I16 the TRS-AN-E channels, STRING the identity,
# ARRAY OF BYTE the 0x10F3 messages of no fixed size: docs/trscat.md "Objects tab").
TYPE_NAMES = TypeNames({
    DataType.BOOLEAN: "Bool", DataType.INTEGER8: "I8", DataType.INTEGER16: "I16",
    DataType.INTEGER32: "I32", DataType.UNSIGNED8: "U8", DataType.UNSIGNED16: "U16",
    DataType.UNSIGNED32: "U32", DataType.VISIBLE_STRING: "STRING",
    DataType.OCTET_STRING: "ARRAY OF BYTE"})


class TrsObjects(Protocol):
    """What the dictionary reads and writes on the device."""

    serial: int
    sync: SyncUnit
    diag: DiagHistory
    f030: list[int]  # sub 0..8
    f050: list[int]  # sub 0..8
    error_values: list[int]  # 0xF700:1..8
    error_modes: list[int]  # 0xF701:1..8
    sysok_mask: int  # 0xF710:1

    def od_error_register(self) -> int: ...
    def od_set_sync_mode(self, index: int, value: int) -> None: ...
    def od_write_f030(self, sub: int, value: int) -> None: ...
    def od_acknowledge(self, value: int) -> None: ...
    def od_diag_status(self) -> int: ...
    def od_bus_ok(self, sub: int) -> bool: ...
    def od_input(self, slot: int, channel: int) -> int: ...
    def od_output(self, slot: int, channel: int) -> int: ...
    def od_write_output(self, slot: int, channel: int, value: int) -> None: ...


def build_od(dev: TrsObjects, configured: Sequence[ModuleKind | None],
             detected: Sequence[ModuleKind],
             on_write: Callable[[], None] | None = None) -> ObjectDictionary:
    """``configured``: the slots of 0xF030 (PDO assignment); ``detected``: of 0xF050.
    ``on_write`` is called before every write that reaches the model (an entry's setter), so
    a write straight into the dictionary wakes the device as a command does."""
    od = ObjectDictionary()
    _identity(od, dev)
    _diagnostics(od, dev)
    for index, io in ((0x1C32, "output"), (0x1C33, "input")):
        _sync_manager(od, dev, index, io)
    add_pdo_mappings(od, configured)
    for slot, kind in enumerate(detected):
        add_slot_objects(od, slot, kind, dev.od_input, dev.od_output, dev.od_write_output)
    _modular_device(od, dev)
    _outputs_on_error(od, dev)
    if on_write is not None:
        announce = on_write
        od.announce_writes(lambda _e, _v: announce())
    return od


def _ro(od: ObjectDictionary, index: int, sub: int, name: str, dtype: DataType, value: Any,
        **kw: Any) -> None:
    od.add(OdEntry(index, sub, name, dtype, RO, value, **kw))


def _identity(od: ObjectDictionary, dev: TrsObjects) -> None:
    _ro(od, 0x1000, 0, "Device type", U32, DEVICE_TYPE)
    # seed 001 names no bits of 0x1001: DS 301's words (docs/trscat.md)
    _ro(od, 0x1001, 0, "Error register", U8, 0, getter=dev.od_error_register,
        explain=REGISTER_WORDS.said)
    _ro(od, 0x1008, 0, "Device name", DataType.VISIBLE_STRING, DEVICE_NAME)
    _ro(od, 0x1009, 0, "Hardware version", DataType.VISIBLE_STRING, HW_VERSION)
    _ro(od, 0x100A, 0, "Software version", DataType.VISIBLE_STRING, SW_VERSION)
    _ro(od, 0x1018, 0, "Identity", U8, 4)
    _ro(od, 0x1018, 1, "Vendor ID", U32, VENDOR_ID)
    _ro(od, 0x1018, 2, "Product code", U32, PRODUCT_CODE)
    _ro(od, 0x1018, 3, "Revision number", U32, REVISION)
    _ro(od, 0x1018, 4, "Serial number", U32, dev.serial)


def _diagnostics(od: ObjectDictionary, dev: TrsObjects) -> None:
    # §9.3.7 0x10F1:2; sub 0 is the highest sub-index (sub 1 is not implemented).
    _ro(od, 0x10F1, 0, "Error Settings", U8, 2)
    _ro(od, 0x10F1, 2, "Sync error counter limit", U32, SYNC_ERROR_LIMIT)
    diag = dev.diag
    _ro(od, 0x10F3, 0, "Diagnosis History", U8, LAST_MESSAGE_SUB)
    _ro(od, 0x10F3, 1, "Maximum Messages", U8, MAX_MESSAGES)
    _ro(od, 0x10F3, 2, "Newest message", U8, 0, getter=lambda: diag.newest)
    od.add(OdEntry(0x10F3, 3, "Newest acknowledged message", U8, RW, 0,
                   getter=lambda: diag.newest_ack, setter=dev.od_acknowledge))
    _ro(od, 0x10F3, 4, "New message available", BOOL, False, pdo_mappable=True,
        getter=lambda: diag.new_available)
    od.add(OdEntry(0x10F3, 5, "Flags", U16, RW, 0, getter=lambda: diag.flags,
                   setter=diag.set_flags, explain=FLAG_WORDS.said))
    # ETG.1020 messages are OCTET_STRINGs (§9.3.7 prints no type for them); a place never
    # written holds no bytes.
    for sub in range(FIRST_MESSAGE_SUB, LAST_MESSAGE_SUB + 1):
        _ro(od, 0x10F3, sub, f"Diagnosis message {sub - FIRST_MESSAGE_SUB + 1:02d}",
            DataType.OCTET_STRING, b"", getter=lambda s=sub: diag.raw(s))


def _sync_manager(od: ObjectDictionary, dev: TrsObjects, index: int, io: str) -> None:
    """§9.3.1: 0x1C32 (SM2, outputs) / 0x1C33 (SM3, inputs), the subs the seed lists."""
    sync = dev.sync
    _ro(od, index, 0, f"SM {io} parameter", U8, 32)
    od.add(OdEntry(index, 1, "Sync mode", U16, RW, 0, getter=lambda: int(sync.mode),
                   setter=lambda v: dev.od_set_sync_mode(index, v)))
    _ro(od, index, 2, "Cycle time", U32, 0, getter=lambda: sync.cycle_ns)
    _ro(od, index, 4, "Sync modes supported", U16, SYNC_MODES_SUPPORTED)
    _ro(od, index, 5, "Minimum cycle time", U32, MIN_CYCLE_NS)
    _ro(od, index, 6, "Calc and copy time", U32, CALC_COPY_NS)
    _ro(od, index, 9, "Delay time", U32, DELAY_NS)
    _ro(od, index, 11, "SM event missed counter", U32, 0, getter=lambda: sync.sm_missed)
    _ro(od, index, 32, "Sync error", BOOL, False, getter=lambda: sync.sync_error)


def _modular_device(od: ObjectDictionary, dev: TrsObjects) -> None:
    # ETG.5001 0xF000, named in §9.3.2.
    _ro(od, 0xF000, 0, "Modular Device Profile", U8, 2)
    _ro(od, 0xF000, 1, "Index distance", U16, 0x0010)
    _ro(od, 0xF000, 2, "Maximum number of modules", U16, MAX_SLOTS)
    # §9.3.2 0xF030 / 0xF050: sub 0 = slots occupied (1..8), sub 1 = integrated, 2..8 = exp.
    od.add(OdEntry(0xF030, 0, "Subindex0", U8, RW_PREOP, 1, low=1, high=MAX_SLOTS,
                   getter=lambda: dev.f030[0], setter=lambda v: dev.od_write_f030(0, v)))
    _ro(od, 0xF050, 0, "Subindex0", U8, 1, getter=lambda: dev.f050[0])
    for sub in range(1, MAX_SLOTS + 1):
        name = "Id oggetto integrato" if sub == 1 else f"Id oggetto espansione {sub - 1}"
        od.add(OdEntry(0xF030, sub, name, U32, RW_PREOP, 0, getter=lambda s=sub: dev.f030[s],
                       setter=lambda v, s=sub: dev.od_write_f030(s, v)))
        _ro(od, 0xF050, sub, name, U32, 0, getter=lambda s=sub: dev.f050[s])
    # §9.3.4 0xF100, mapped in 0x1AFF.
    _ro(od, 0xF100, 0, "Subindex0", U8, 4)
    _ro(od, 0xF100, 1, "Diagnostic status", U8, 0, pdo_mappable=True,
        getter=dev.od_diag_status)
    for sub, name in ((2, "TRS bus communication status"), (3, "TRS bus voltage status"),
                      (4, "TRS bus current status")):
        _ro(od, 0xF100, sub, name, BOOL, True, pdo_mappable=True,
            getter=lambda s=sub: dev.od_bus_ok(s))


def _outputs_on_error(od: ObjectDictionary, dev: TrsObjects) -> None:
    # §9.3.5 0xF700 / 0xF701, §9.3.6 0xF710.
    for index, attr, label in ((0xF700, "error_values", "Error Value"),
                               (0xF701, "error_modes", "Error Mode")):
        _ro(od, index, 0, "Subindex0", U8, MAX_SLOTS)
        for sub in range(1, MAX_SLOTS + 1):
            where = "oggetto integrato" if sub == 1 else f"espansione {sub - 1}"
            od.add(OdEntry(index, sub, f"{label} {where}", U16, RW, 0,
                           getter=lambda s=sub, a=attr: getattr(dev, a)[s - 1],
                           setter=lambda x, s=sub, a=attr: getattr(dev, a).__setitem__(
                               s - 1, int(x))))
    _ro(od, 0xF710, 0, "Subindex0", U8, 1)
    od.add(OdEntry(0xF710, 1, "SysOK Mask", U16, RW, 0, getter=lambda: dev.sysok_mask,
                   setter=lambda x: setattr(dev, "sysok_mask", int(x))))


def refuse_in_state(index: int, sub: int) -> SdoAbort:
    """A write the present ESM state does not allow (0xF030 outside PRE-OP, §9.3.2)."""
    return SdoAbort(AbortCode.CANNOT_STORE_STATE, index, sub)
