"""The node's dictionary as a ``canopen`` ObjectDictionary: the source of the EDS file.

The same definitions serve the SDO server and the EDS, so a standard tool sees exactly what
the node answers. COB-IDs that depend on the node-ID are written the EDS way
(``$NODEID+0x180``); values that change while the drive runs (statusword, positions) get no
default. Device information follows ch. 4 "Caratteristiche principali": 4 RPDO, 4 TPDO, byte
granularity, the eight bit rates of n1, a simple boot-up slave, no LSS.
"""

from __future__ import annotations

import io
from typing import Any

from canopen.objectdictionary import ObjectDictionary, ODRecord, ODVariable
from canopen.objectdictionary import eds as canopen_eds

from devices.canopen.comm_objects import RECORD_NAMES, VENDOR_ID
from devices.canopen.dictionary import CanOpenDictionary
from devices.canopen.pdo import DUMMY_BITS
from devices.od import Access, OdEntry
from devices.servo.parameters import CAN_KBAUD_BY_N1

VENDOR_NAME = "Selema"
PRODUCT_NAME = "Servo drive (CANopen, DSP 402)"
FILE_INFO = {  # fixed, so the committed file only changes when the dictionary does
    "FileName": "servo_drive.eds",
    "FileVersion": "1",
    "FileRevision": "0",
    "EdsVersion": "4.0",
    "Description": "Servo drive, CANopen DS 301 v4.01 / DSP 402 v1.1 (seed 004 ch. 4)",
    "CreationDate": "11-22-2026",
    "CreationTime": "12:00PM",
    "ModificationDate": "11-22-2026",
    "ModificationTime": "12:00PM",
    "CreatedBy": "FieldRig (python -m app.canopen_eds)",
}
# Node-ID relative defaults, in the EDS notation.
_RELATIVE = frozenset({(0x1014, 0), *((0x1400 + i, 1) for i in range(4)),
                       *((0x1800 + i, 1) for i in range(4))})
SUB0_NAME = "Number of entries"


def _variable(entry: OdEntry, value: Any, node_id: int, name: str = "") -> ODVariable:
    var = ODVariable(name or entry.name, entry.index, entry.sub)
    var.data_type = int(entry.dtype)
    var.access_type = entry.access.value
    var.pdo_mappable = entry.pdo_mappable
    if (entry.index, entry.sub) in _RELATIVE:
        # "$NODEID+0x80000280": the invalid bit (31) stays in the constant part
        var.default_raw = f"$NODEID+0x{value - node_id:X}"
        var.default = value
        var.relative = True
    elif not (entry.access is Access.RO and entry.pdo_mappable):  # process values: no default
        var.default = value
    if entry.low is not None:
        var.min = entry.low
    if entry.high is not None:
        var.max = entry.high
    return var


def build_canopen_od(dictionary: CanOpenDictionary, node_id: int = 1) -> ObjectDictionary:
    """One ODVariable per single sub-0 object, one ODRecord per object with sub-indices."""
    od = ObjectDictionary()
    info = od.device_information
    info.vendor_name, info.vendor_number = VENDOR_NAME, VENDOR_ID
    info.product_name = PRODUCT_NAME
    info.simple_boot_up_slave, info.simple_boot_up_master = True, False
    info.granularity = 8
    info.nr_of_RXPDO = info.nr_of_TXPDO = 4  # type: ignore[assignment]
    info.LSS_supported = False
    info.dynamic_channels_supported = info.group_messaging = False
    info.allowed_baudrates = {kbaud * 1000 for kbaud in CAN_KBAUD_BY_N1.values()}
    groups: dict[int, list[OdEntry]] = {}
    for entry in dictionary:
        groups.setdefault(entry.index, []).append(entry)
    for index, entries in groups.items():
        values = [_default(dictionary, e) for e in entries]
        if len(entries) == 1 and entries[0].sub == 0:
            od.add_object(_variable(entries[0], values[0], node_id))
            continue
        name = RECORD_NAMES.get(index, entries[0].name)
        record = ODRecord(name, index)
        for entry, value in zip(entries, values, strict=True):
            named_after_object = entry.sub == 0 and entry.name == name
            record.add_member(_variable(entry, value, node_id,
                                        SUB0_NAME if named_after_object else ""))
        od.add_object(record)
    for index in DUMMY_BITS:  # RPDOs take dummy entries: [DummyUsage] says so
        dummy = ODVariable(f"Dummy{index:04d}", index)
        dummy.data_type, dummy.access_type = index, "const"
        od.add_object(dummy)
    return od


def _default(dictionary: CanOpenDictionary, entry: OdEntry) -> Any:
    try:
        return dictionary.peek(entry.index, entry.sub)
    except Exception:  # a live value that cannot be read now (e.g. powered off)
        return entry.default


def eds_text(dictionary: CanOpenDictionary) -> str:
    """The EDS file (canopen's EDS writer, with fixed file information)."""
    out = io.StringIO()
    canopen_eds.export_eds(build_canopen_od(dictionary), out, file_info=dict(FILE_INFO))
    return out.getvalue()
