"""The DS 301 communication objects of the drive's CANopen node (0x1000..0x1A03).

Seed 004 ch. 4 "Oggetti implementati": mandatory objects (0x1000 const, 0x1001 ro, 0x1003
sub 0 rw / sub 1 ro, 0x1018 sub 0 / sub 1 ro) and optional ones (0x1005, 0x1008/9/A const
6 B, 0x100C, 0x100D, 0x1010, 0x1014, 0x1015, 0x1017, the PDO records). 0x1010 (save) is the
drive's own (devices/servo/od_map.py). 0x1006 (cycle period) is described in the general part
of ch. 4 ("In [1006] ... l'intervallo di sincronizzazione in microsecondi") and kept as a
stored value. Every object is a view on the node's state: a write goes through the node, so
changing the heartbeat time restarts the heartbeat, and a refused write changes nothing.
Where the seed prints no value, the choice is in docs/canopen.md §Identity.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from devices.canopen.emcy import REGISTER_WORDS
from devices.canopen.pdo import MAX_ENTRIES, Pdo
from devices.od import AbortCode, Access, DataType, ObjectDictionary, OdEntry, SdoAbort
from devices.servo.alarms import error_field_text

if TYPE_CHECKING:
    from devices.canopen.node import CanOpenNode

D = DataType
RO, RW, CONST = Access.RO, Access.RW, Access.CONST

DEVICE_TYPE = 0x0002_0192  # DSP 402 (0x192) servo drive (additional information 0x0002)
VENDOR_ID = 0x0000_078F  # ch. 5: "Il Vendor ID per il consorzio ETG è: 0x0000078F"
DEVICE_NAME = "SDrive"  # 0x1008, 6 B printed
HARDWARE_VERSION = "HW1.00"  # 0x1009, 6 B printed
SOFTWARE_VERSION = "FW3.05"  # 0x100A, 6 B: the firmware notes of ch. 4 go up to 3.05
DRIVE_MANUFACTURER = "Selema (Italy)"  # 0x6504, 14 B printed; TwinCAT lists "Selema" (ch. 5)
CATALOG_ADDRESS = "http://example.it/"  # 0x6505, 18 B printed; a placeholder address
SYNC_COB_ID = 0x80  # "COB ID di default: 0x80" (ch. 4, interpolator example)
COB_PRODUCER = 0x4000_0000  # 0x1005 bit 30: this node generates SYNC (it does not)
COB_EXTENDED = 0x2000_0000
# Names of the records whose sub 0 is a count (the EDS names the object, not its sub 0).
RECORD_NAMES: dict[int, str] = {
    0x1003: "Pre-defined error field", 0x1018: "Identity object",
    **{0x1400 + i: f"Receive PDO {i + 1} communication parameter" for i in range(4)},
    **{0x1600 + i: f"Receive PDO {i + 1} mapping parameter" for i in range(4)},
    **{0x1800 + i: f"Transmit PDO {i + 1} communication parameter" for i in range(4)},
    **{0x1A00 + i: f"Transmit PDO {i + 1} mapping parameter" for i in range(4)},
}


def _check_cob_id(index: int, value: int) -> int:
    """An 11-bit COB-ID: bit 29 (29-bit frame) and bits 11-28 are refused, 0x06090030 as CiA
    301 has it for a frame type the device lacks; bit 31 is left to the caller's meaning
    (0x1014 valid / not valid, 0x1005 "do not care")."""
    if value & 0x7FFF_F800:
        raise SdoAbort(AbortCode.VALUE_RANGE, index, 0)
    return value


def build_comm_objects(node: CanOpenNode) -> ObjectDictionary:
    od = ObjectDictionary()

    def add(index: int, sub: int, name: str, dtype: DataType, access: Access,
            get: Callable[[], Any], put: Callable[[Any], None] | None = None) -> None:
        od.add(OdEntry(index, sub, name, dtype, access, default=get(), getter=get,
                       setter=put))

    def const(index: int, sub: int, name: str, dtype: DataType, value: Any) -> None:
        add(index, sub, name, dtype, CONST if dtype is D.VISIBLE_STRING or index == 0x1000
            else RO, lambda: value)

    const(0x1000, 0, "Device type", D.UNSIGNED32, DEVICE_TYPE)
    od.add(OdEntry(0x1001, 0, "Error register", D.UNSIGNED8, RO,
                   default=node.error_register, getter=lambda: node.error_register,
                   explain=REGISTER_WORDS.said))  # seed 004 ch. 4 prints DS 301's bits
    add(0x1003, 0, "Number of errors", D.UNSIGNED8, RW, lambda: node.history.count,
        node.clear_history)
    od.add(OdEntry(0x1003, 1, "Standard error field", D.UNSIGNED32, RO,
                   default=node.history.latest, getter=lambda: node.history.latest,
                   explain=lambda v: error_field_text(v, node.drive.alarm_table)))
    add(0x1005, 0, "COB-ID SYNC", D.UNSIGNED32, RW, lambda: node.sync_cob_id,
        lambda v: setattr(node, "sync_cob_id", _check_sync(v)))
    add(0x1006, 0, "Communication cycle period", D.UNSIGNED32, RW,
        lambda: node.cycle_period_us, lambda v: setattr(node, "cycle_period_us", v))
    const(0x1008, 0, "Manufacturer device name", D.VISIBLE_STRING, node.device_name)
    const(0x1009, 0, "Manufacturer hardware version", D.VISIBLE_STRING, HARDWARE_VERSION)
    const(0x100A, 0, "Manufacturer software version", D.VISIBLE_STRING, SOFTWARE_VERSION)
    add(0x100C, 0, "Guard time", D.UNSIGNED16, RW, lambda: node.guard.guard_time_ms,
        node.set_guard_time)
    add(0x100D, 0, "Life time factor", D.UNSIGNED8, RW, lambda: node.guard.life_time_factor,
        node.set_life_time_factor)
    add(0x1014, 0, "COB-ID EMCY", D.UNSIGNED32, RW, lambda: node.emcy_cob_id,
        lambda v: setattr(node, "emcy_cob_id", _check_cob_id(0x1014, v)))
    add(0x1015, 0, "Inhibit time EMCY", D.UNSIGNED16, RW, lambda: node.emcy.inhibit_100us,
        lambda v: setattr(node.emcy, "inhibit_100us", v))
    add(0x1017, 0, "Producer heartbeat time", D.UNSIGNED16, RW, lambda: node.heartbeat_ms,
        node.set_heartbeat)
    const(0x1018, 0, "Identity object", D.UNSIGNED8, 1)
    const(0x1018, 1, "Vendor-ID", D.UNSIGNED32, VENDOR_ID)
    for pdo in (*node.rpdos, *node.tpdos):
        _pdo_objects(od, node, pdo)
    return od


def _check_sync(value: int) -> int:
    """0x1005 as CiA 301 lays it out (the seed's table refers to DS 301, docs/canopen.md
    §Objects): bit 31 "x", do not care, so accepted and kept as written; bit 30 "gen" refused
    with 0x06090030, as CiA 301 says for a device that cannot generate SYNC."""
    if value & COB_PRODUCER:  # the drive consumes SYNC, it cannot produce it
        raise SdoAbort(AbortCode.VALUE_RANGE, 0x1005, 0)
    return _check_cob_id(0x1005, value)


def _pdo_objects(od: ObjectDictionary, node: CanOpenNode, pdo: Pdo) -> None:
    comm, mapping, kind = pdo.comm_index, pdo.map_index, "Receive" if pdo.receive else "Transmit"

    def add(index: int, sub: int, name: str, dtype: DataType, access: Access,
            get: Callable[[], Any], put: Callable[[Any], None] | None = None) -> None:
        od.add(OdEntry(index, sub, name, dtype, access, default=get(), getter=get,
                       setter=put))

    # RPDO records have sub 1-2 (inhibit time and event timer "non ha significato per
    # RxPDOs"); TPDO records have 1-5 as printed (sub 4: compatibility entry).
    add(comm, 0, "Highest sub-index supported", D.UNSIGNED8, RO,
        lambda: 2 if pdo.receive else 5)
    add(comm, 1, "COB-ID", D.UNSIGNED32, RW, lambda: pdo.cob_id,
        lambda v: node.set_pdo_cob_id(pdo, v))
    add(comm, 2, "Transmission type", D.UNSIGNED8, RW, lambda: pdo.trans_type, pdo.set_type)
    if not pdo.receive:
        add(comm, 3, "Inhibit time", D.UNSIGNED16, RW, lambda: pdo.inhibit_100us,
            lambda v: setattr(pdo, "inhibit_100us", v))
        add(comm, 4, "Compatibility entry", D.UNSIGNED8, RW, lambda: pdo.compatibility,
            lambda v: setattr(pdo, "compatibility", v))
        add(comm, 5, "Event timer", D.UNSIGNED16, RW, lambda: pdo.event_timer_ms,
            lambda v: node.set_event_timer(pdo, v))
    add(mapping, 0, "Number of mapped objects", D.UNSIGNED8, RW, lambda: pdo.count,
        lambda v: node.set_pdo_count(pdo, v))
    for sub in range(1, MAX_ENTRIES + 1):
        add(mapping, sub, f"{kind} PDO {pdo.number} mapping entry {sub}", D.UNSIGNED32, RW,
            lambda s=sub: pdo.entries[s - 1],
            lambda v, s=sub: pdo.set_entry(s, v, node.dictionary.entry))


def build_profile_extras() -> ObjectDictionary:
    """DSP 402 objects of the ch. 4 table that the drive model leaves to the fieldbus side."""
    od = ObjectDictionary()
    od.add(OdEntry(0x6504, 0, "Drive manufacturer", D.VISIBLE_STRING, RO,
                   DRIVE_MANUFACTURER, getter=lambda: DRIVE_MANUFACTURER))
    od.add(OdEntry(0x6505, 0, "Http drive catalog address", D.VISIBLE_STRING, RO,
                   CATALOG_ADDRESS, getter=lambda: CATALOG_ADDRESS))
    od.add(OdEntry(0x67FF, 0, "Single device type", D.UNSIGNED32, RW, DEVICE_TYPE))
    return od
