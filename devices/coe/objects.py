"""The CoE objects of the drive slave, and the dictionary a CoE master sees.

Seed 004 ch. 5 "SDO: tipologia e dizionario oggetti": "Il dizionario oggetti, accessibile via
SDO, è lo stesso del CANOpen ... L'unica differenza sta nell'aggiunta dell'oggetto 0x603F".
So: the drive's objects (devices/servo/od_map.py, with 0x603F and 0x2007) + the DSP 402
extras of the CANopen node (0x6504, 0x6505, 0x67FF) + these communication objects:

- 0x1000, 0x1001, 0x1003, 0x1008..0x100A as on CANopen (same values: one drive);
- 0x1018 with the four entries an EtherCAT master compares with the ESI (vendor 0x0000078F,
  ch. 5; product code, revision and serial are not printed: docs/ethercat-coe.md §Identity);
- 0x1600..0x1603 / 0x1A00..0x1A03 (ch. 5 contents), 0x1C00 (sync manager types), 0x1C12 /
  0x1C13 (ch. 5 "Mappatura dinamica PDO");
- 0x6040, 0x6060, 0x6061, 0x6502 seen through CSP (devices/coe/csp.py).

Objects of CANopen's CAN layer have no meaning on EtherCAT and are absent (0x06020000): SYNC /
EMCY COB-IDs, guarding, heartbeat, the PDO communication records 0x1400.. / 0x1800...
PDO mapping and assignment are written in PREOP only (ch. 5 "P -> S: Il Master configura ...
la mappatura dei process data"): later they abort 0x08000022.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from devices.canopen.comm_objects import (
    DEVICE_NAME,
    DEVICE_TYPE,
    HARDWARE_VERSION,
    SOFTWARE_VERSION,
    VENDOR_ID,
    build_profile_extras,
)
from devices.canopen.dictionary import CanOpenDictionary
from devices.canopen.emcy import REGISTER_WORDS
from devices.canopen.pdo import MAX_ENTRIES, Pdo
from devices.coe.assignment import PDOS_PER_DIRECTION, Assignment
from devices.coe.csp import CSP_SUPPORTED
from devices.coe.emergency import error_register
from devices.ethercat import AlState
from devices.od import AbortCode, Access, DataType, ObjectDictionary, OdEntry, SdoAbort
from devices.servo.alarms import error_field_text
from devices.servo.od_map import SUPPORTED_DRIVE_MODES

if TYPE_CHECKING:
    from devices.coe.drive_slave import DriveEcatSlave

D = DataType
RO, RW, WO, CONST = Access.RO, Access.RW, Access.WO, Access.CONST
# PDO mapping and assignment: read in every state, written in PREOP only (_in_preop), which
# the Objects tab and SDO information then say (ETG.1000.6 access word 0x000F, not 0x003F)
RW_PREOP = Access.RW_PREOP

PRODUCT_CODE = 0x0000_0011  # not printed; 11 = c9's EtherCAT code
REVISION = 0x0000_0305  # not printed; the firmware 3.05 of 0x100A
# Sync manager communication types (ETG.1000.6 0x1C00): mailbox out, mailbox in, outputs,
# inputs, as ch. 5's TwinCAT screen shows SM 0 MbxOut, 1 MbxIn, 2 Outputs, 3 Inputs.
SM_TYPES = (1, 2, 3, 4)


def build_coe_dictionary(slave: DriveEcatSlave) -> CanOpenDictionary:
    """The lookup a CoE master sees. An index belongs to the first dictionary that has it:
    the slave's objects (with CSP's views of 0x6040 / 0x6060 / 0x6061 / 0x6502) and the
    CANopen extras, then the drive's. CanOpenDictionary leaves out the drive's EtherCAT-only
    objects (0x603F, 0x2007) on purpose; on CoE they exist, so the drive's dictionary is also
    given as the last one, where they are found."""
    drive_od = slave.drive.od
    return CanOpenDictionary(build_slave_objects(slave), drive_od, drive_od)


def build_slave_objects(slave: DriveEcatSlave) -> ObjectDictionary:
    od = ObjectDictionary()

    def add(index: int, sub: int, name: str, dtype: DataType, access: Access,
            get: Callable[[], Any], put: Callable[[Any], None] | None = None,
            mappable: bool = False) -> None:
        od.add(OdEntry(index, sub, name, dtype, access, default=get(), getter=get,
                       setter=put, pdo_mappable=mappable))

    def const(index: int, sub: int, name: str, dtype: DataType, value: Any) -> None:
        add(index, sub, name, dtype, CONST if dtype is D.VISIBLE_STRING or index == 0x1000
            else RO, lambda: value)

    drive, csp, emcy = slave.drive, slave.csp, slave.emergencies
    const(0x1000, 0, "Device type", D.UNSIGNED32, DEVICE_TYPE)
    od.add(OdEntry(0x1001, 0, "Error register", D.UNSIGNED8, RO,
                   default=error_register(drive), getter=lambda: error_register(drive),
                   explain=REGISTER_WORDS.said))  # seed 004 ch. 4 prints DS 301's bits
    add(0x1003, 0, "Number of errors", D.UNSIGNED8, RW, lambda: emcy.history.count,
        _clear_history(slave))
    od.add(OdEntry(0x1003, 1, "Standard error field", D.UNSIGNED32, RO,
                   default=emcy.history.latest, getter=lambda: emcy.history.latest,
                   explain=lambda v: error_field_text(v, drive.alarm_table)))
    const(0x1008, 0, "Manufacturer device name", D.VISIBLE_STRING, DEVICE_NAME)
    const(0x1009, 0, "Manufacturer hardware version", D.VISIBLE_STRING, HARDWARE_VERSION)
    const(0x100A, 0, "Manufacturer software version", D.VISIBLE_STRING, SOFTWARE_VERSION)
    const(0x1018, 0, "Identity object", D.UNSIGNED8, 4)
    const(0x1018, 1, "Vendor-ID", D.UNSIGNED32, VENDOR_ID)
    const(0x1018, 2, "Product code", D.UNSIGNED32, PRODUCT_CODE)
    const(0x1018, 3, "Revision number", D.UNSIGNED32, REVISION)
    const(0x1018, 4, "Serial number", D.UNSIGNED32, slave.serial)
    for pdo in (*slave.rx_pdos, *slave.tx_pdos):
        _mapping_objects(od, slave, pdo)
    const(0x1C00, 0, "Sync manager communication type", D.UNSIGNED8, len(SM_TYPES))
    for sub, kind in enumerate(SM_TYPES, start=1):
        const(0x1C00, sub, f"Communication type SM{sub - 1}", D.UNSIGNED8, kind)
    for assignment in (slave.rx_assign, slave.tx_assign):
        _assignment_objects(od, slave, assignment)
    # ---- CSP's views of the drive's objects (devices/coe/csp.py) ------------------------------
    add(0x6040, 0, "Controlword", D.UNSIGNED16, RW, csp.controlword, csp.write_controlword,
        mappable=True)
    add(0x6060, 0, "Modes of operation", D.INTEGER8, WO, csp.mode_display, csp.write_mode,
        mappable=True)
    add(0x6061, 0, "Modes of operation display", D.INTEGER8, RO, csp.mode_display,
        mappable=True)
    const(0x6502, 0, "Supported drive modes", D.UNSIGNED32, SUPPORTED_DRIVE_MODES | CSP_SUPPORTED)
    for entry in build_profile_extras():
        od.add(entry)
    return od


def _clear_history(slave: DriveEcatSlave) -> Callable[[Any], None]:
    def clear(value: Any) -> None:
        if value != 0:  # ch. 4: "al sub0 può essere scritto solo col valore 0"
            raise SdoAbort(AbortCode.VALUE_RANGE, 0x1003, 0)
        slave.emergencies.history.clear()
    return clear


def _in_preop(slave: DriveEcatSlave, index: int, sub: int, change: Callable[[], None]) -> None:
    if slave.esm.state is not AlState.PREOP:
        raise SdoAbort(AbortCode.CANNOT_STORE_STATE, index, sub)
    change()
    slave.configuration_changed()


def _mapping_objects(od: ObjectDictionary, slave: DriveEcatSlave, pdo: Pdo) -> None:
    index, kind = pdo.map_index, "RxPDO" if pdo.receive else "TxPDO"
    lookup = slave.dictionary_entry
    od.add(OdEntry(index, 0, "Number of mapped objects", D.UNSIGNED8, RW_PREOP, pdo.count,
                   getter=lambda: pdo.count,
                   setter=lambda v: _in_preop(slave, index, 0, lambda: pdo.set_count(v, lookup))))
    for sub in range(1, MAX_ENTRIES + 1):
        od.add(OdEntry(index, sub, f"{kind} {pdo.number} mapping entry {sub}", D.UNSIGNED32,
                       RW_PREOP, pdo.entries[sub - 1], getter=lambda s=sub: pdo.entries[s - 1],
                       setter=lambda v, s=sub: _in_preop(
                           slave, index, s, lambda: pdo.set_entry(s, v, lookup))))


def _assignment_objects(od: ObjectDictionary, slave: DriveEcatSlave, a: Assignment) -> None:
    kind = "RxPDO" if a.index == 0x1C12 else "TxPDO"
    od.add(OdEntry(a.index, 0, f"{kind} assign", D.UNSIGNED8, RW_PREOP, a.count,
                   getter=lambda: a.count,
                   setter=lambda v: _in_preop(slave, a.index, 0, lambda: a.set_count(v))))
    for sub in range(1, PDOS_PER_DIRECTION + 1):
        od.add(OdEntry(a.index, sub, f"Assigned {kind} {sub}", D.UNSIGNED16, RW_PREOP,
                       a.entries[sub - 1], getter=lambda s=sub: a.entries[s - 1],
                       setter=lambda v, s=sub: _in_preop(
                           slave, a.index, s, lambda: a.set_entry(s, v))))
