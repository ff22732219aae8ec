"""What every face does the same way: identity, sync managers, AL control, images from mapping.

A face translates between a slave model and the wire; it never decides. The model decides
whether a requested state is allowed and with which AL status code (``request_state``), what
its objects hold (its ``od``) and what its outputs do. Faces run in the simulation thread only.

Sync manager layout (the same for every slave, SII category 41; defined in
devices/sync_managers.py, as a slave that checks what its master wrote knows it): SM0 mailbox
out 0x1000 and SM1 mailbox in 0x1080, 128 bytes each; SM2 outputs at 0x1100, SM3 inputs at
0x1400 (room for 768 output bytes, more than any slave of the rig maps). Control bytes are the
usual ones: 0x26 (mailbox, write, PDI IRQ), 0x22 (mailbox, read), 0x64 (3-buffer, write,
watchdog), 0x20 (3-buffer, read). An SM with no process data is disabled (length 0, enable 0).
The SM registers a master writes go to the model (``configure_sync_managers``), which checks
them at its transitions (the TRS-CAT, seed 001 §9.2).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from app.ethercat_wire.description import (
    DiagText,
    Pdo,
    PdoEntry,
    SlaveDescription,
    SlotModule,
    SyncManager,
)
from app.ethercat_wire.faces import image
from devices.ethercat import AlState
from devices.od import (
    Access,
    DataType,
    ObjectDictionary,
    OdEntry,
    SdoAbort,
    download_value,
    encode,
)
from devices.sync_managers import (  # the layout the slaves check (their ESI)
    INPUTS_START,
    MAILBOX_IN,
    MAILBOX_OUT,
    MAILBOX_SIZE,
    OUTPUTS_START,
    SM_CONTROL,
    SmSetup,
)

logger = logging.getLogger(__name__)

RX_ASSIGN, TX_ASSIGN = 0x1C12, 0x1C13
SM_COMM_TYPE = 0x1C00
SM_TYPES = (1, 2, 3, 4)  # ETG.1000.6 0x1C00: mailbox out, mailbox in, outputs, inputs
COE_SDO, COE_SDO_INFO, COE_PDO_ASSIGN, COE_PDO_CONFIG = 0x01, 0x02, 0x04, 0x08  # SII GENERAL
COE_COMPLETE_ACCESS = 0x20  # the same byte (ETG.2010); the CoE server serves it only then


def _sm_type_objects(od: ObjectDictionary | None = None) -> ObjectDictionary:
    od = od if od is not None else ObjectDictionary()
    od.add(OdEntry(SM_COMM_TYPE, 0, "Sync manager type", DataType.UNSIGNED8, Access.RO,
                   len(SM_TYPES)))
    for sm, kind in enumerate(SM_TYPES):
        od.add(OdEntry(SM_COMM_TYPE, sm + 1, f"SM{sm} type", DataType.UNSIGNED8, Access.RO,
                       kind))
    return od


# 0x1C00 describes the sync managers, which the wire lays out (the table above), so the wire
# answers it for a slave whose dictionary has the PDO assignment but not 0x1C00: a master reads
# it before 0x1C12 / 0x1C13 (SOEM ecx_readPDOmap) and falls back to the SII PDOs without it.
SM_TYPE_OBJECTS = _sm_type_objects()


def sync_managers(out_bytes: int, in_bytes: int) -> tuple[SyncManager, ...]:
    return (SyncManager(MAILBOX_OUT, MAILBOX_SIZE, SM_CONTROL[0], 1),
            SyncManager(MAILBOX_IN, MAILBOX_SIZE, SM_CONTROL[1], 1),
            SyncManager(OUTPUTS_START, out_bytes, SM_CONTROL[2], 1 if out_bytes else 0),
            SyncManager(INPUTS_START, in_bytes, SM_CONTROL[3], 1 if in_bytes else 0))


@dataclass(frozen=True)
class Layout:
    """One direction's process image: the PDOs, where each mapped object sits, the bytes."""

    pdos: tuple[Pdo, ...]
    fields: tuple[image.Field, ...]
    size: int

    @classmethod
    def of(cls, pdos: tuple[Pdo, ...]) -> Layout:
        return cls(pdos, tuple(image.fields(pdos)), image.byte_size(pdos))


class NoAnswer(Exception):
    """The model's mailbox does not answer (off the line, no application, no dictionary yet):
    no reply goes back, and the master times out as it would on a real device."""


class Face:
    """The wire's view of one kind of slave model. Subclasses name the kind and the ESI data."""

    kind: ClassVar[str]
    name: ClassVar[str]  # SII string 1 / ESI device name
    group: ClassVar[str]
    order_code: ClassVar[str]
    vendor_name: ClassVar[str] = ""  # ESI Vendor Name (the configurator's catalogue folder)
    dc_supported: ClassVar[bool] = False
    dc_default: ClassVar[bool] = False  # DC-Synchron the slave's default mode (ESI order)
    sm_mode_desc: ClassVar[str] = "FreeRun/SM-Synchron"  # the ESI Desc of the non-DC OpMode
    coe_details: ClassVar[int] = COE_SDO | COE_SDO_INFO
    identity_defaults: ClassVar[tuple[int, int, int]]  # vendor, product, revision (no OD yet)

    # The mapping objects change only with a new dictionary (the FastCAT's scan, the TRS-CAT's
    # 0xF030, the CPX-E-EC's restart): layouts are kept per dictionary object. A master cannot
    # edit the PDOs' content then, so it is also the ESI's Fixed flag.
    mapping_fixed: ClassVar[bool] = True

    def __init__(self) -> None:
        self._last_outputs: dict[int, bytes] = {}  # id(model) -> last image applied
        self._layouts: dict[tuple[int, bool], tuple[Any, Layout]] = {}

    # ---- object dictionary -----------------------------------------------------------------
    def od(self, model: Any) -> ObjectDictionary | None:
        """The dictionary a CoE master reads; None while the model has none (off, scanning)."""
        return model.od

    def wire_objects(self, model: Any) -> ObjectDictionary | None:
        """Objects the wire adds to the model's (0x1C00), or None."""
        od = self.od(model)
        if od is None or (SM_COMM_TYPE, 0) in od or (RX_ASSIGN, 0) not in od:
            return None
        return SM_TYPE_OBJECTS

    def _wire(self, model: Any, index: int) -> ObjectDictionary | None:
        extra = self.wire_objects(model)
        return extra if extra is not None and extra.has_index(index) else None

    def upload(self, model: Any, index: int, sub: int) -> Any:
        """SDO upload value (access enforced; raises SdoAbort)."""
        return self._require_od(model).read(index, sub)

    def download(self, model: Any, index: int, sub: int, value: Any) -> None:
        """SDO download of a decoded value (access and range enforced; raises SdoAbort)."""
        self._require_od(model).write(index, sub, value)

    def entry(self, model: Any, index: int, sub: int) -> OdEntry:
        extra = self._wire(model, index)
        return extra.entry(index, sub) if extra is not None else \
            self._require_od(model).entry(index, sub)

    def objects(self, model: Any) -> list[OdEntry]:
        """Every entry a master may list (SDO information), the wire's own included."""
        entries = list(self._require_od(model))
        extra = self.wire_objects(model)
        return sorted([*entries, *(extra or ())], key=lambda e: (e.index, e.sub))

    def bootstrap_mailbox(self, model: Any) -> bool:
        """Whether only the bootstrap mailbox runs (BOOT): CoE gets a mailbox error. A slave
        without BOOT never is there."""
        return False

    def _require_od(self, model: Any) -> Any:
        od = self.od(model)
        if od is None or not model.reachable():
            raise NoAnswer(f"{model.device_id}: no object dictionary on the line now")
        return od

    def upload_raw(self, model: Any, index: int, sub: int) -> bytes:
        """The bytes of an SDO upload, little endian as the object's type packs them."""
        extra = self._wire(model, index)
        value = extra.read(index, sub) if extra is not None else self.upload(model, index, sub)
        return encode(self.entry(model, index, sub).dtype, value)

    def download_raw(self, model: Any, index: int, sub: int, data: bytes) -> None:
        """An SDO download's bytes: their length must be the object's (DS301 0x0607001x)."""
        self.download(model, index, sub, download_value(self.entry(model, index, sub), data))

    # ---- identity and description ---------------------------------------------------------
    def identity(self, model: Any) -> tuple[int, int, int, int]:
        """Vendor, product code, revision, serial: the model's 0x1018."""
        od = self.od(model)
        if od is not None and (0x1018, 4) in od:
            return tuple(int(od.peek(0x1018, s)) for s in (1, 2, 3, 4))  # type: ignore[return-value]
        vendor, product, revision = self.identity_defaults
        return vendor, product, revision, int(model.serial)

    def layout(self, model: Any, receive: bool) -> Layout:
        """SM2 (``receive``: the RxPDOs) or SM3 layout as the mapping objects say now."""
        od = self.od(model)
        key = (id(model), receive)
        cached = self._layouts.get(key)
        if self.mapping_fixed and cached is not None and cached[0] is od:
            return cached[1]
        found = Layout.of(self.read_pdos(model, RX_ASSIGN if receive else TX_ASSIGN))
        self._layouts[key] = (od, found)
        return found

    def rx_pdos(self, model: Any) -> tuple[Pdo, ...]:
        return self.layout(model, True).pdos

    def tx_pdos(self, model: Any) -> tuple[Pdo, ...]:
        return self.layout(model, False).pdos

    def read_pdos(self, model: Any, assign_index: int) -> tuple[Pdo, ...]:
        """The PDOs an assignment object lists, read from the model's dictionary."""
        od = self.od(model)
        if od is None or (assign_index, 0) not in od:
            return ()
        return image.read_pdos(od.peek, od.entry, image.assigned(od.peek, assign_index))

    def spare_pdos(self, model: Any, receive: bool) -> tuple[Pdo, ...]:
        """PDOs the model has but does not assign now (the ESI lists them without Sm)."""
        return ()

    def slot(self, model: Any) -> tuple[str, tuple[SlotModule, ...]]:
        """The ESI slot of a slave whose PDO sets are chosen as modules: name and modules."""
        return "", ()

    def modular(self) -> dict[str, Any]:
        """A modular device's slot layout (SlaveDescription's slot_count ... fields)."""
        return {}

    def object_name(self, index: int, sub0_name: str) -> str:
        """The name SDO Information gives an object: its sub 0's, where the model names sub 0
        after the object (a record whose sub 0 is a count names it in ``object_name``)."""
        return sub0_name

    def pdo_name(self, pdo: Pdo) -> str:
        """A PDO's name for the SII / ESI: the name the model gives its mapping object."""
        return pdo.name

    def pdo_entry_name(self, entry: PdoEntry) -> str:
        """A mapped entry's name for the SII / ESI: its object's, unless the device names it
        otherwise in its PDOs."""
        return entry.name

    def pdo_entry_type(self, entry: PdoEntry) -> str:
        """A mapped entry's ESI DataType (SII: its code): its object's type, read with the
        mapping; "" types it unsigned by its bit length."""
        return entry.data_type

    def named_pdo(self, pdo: Pdo) -> Pdo:
        """A PDO as the SII / ESI show it: the face's names, types and Mandatory flag."""
        return replace(pdo, name=self.pdo_name(pdo), mandatory=self.pdo_mandatory(pdo),
                       entries=tuple(replace(e, name=self.pdo_entry_name(e),
                                             data_type=self.pdo_entry_type(e))
                                     for e in pdo.entries))

    def module_pdo(self, od: Any, index: int) -> tuple[Pdo, ...]:
        """A catalogue module's PDO of mapping object ``index`` for the ESI's Modules; none
        where the module has no such mapping or it maps nothing (no empty mapping is assigned:
        FastCAT §5, TRS-CAT §9.3.3)."""
        if (index, 0) not in od or not od.peek(index, 0):
            return ()
        return (self.named_pdo(image.read_pdo(od.peek, od.entry, index)),)

    def pdo_mandatory(self, pdo: Pdo) -> bool:
        """Whether the ESI marks the PDO Mandatory (a configurator cannot unassign it)."""
        return False

    def describe(self, model: Any) -> SlaveDescription:
        vendor, product, revision, serial = self.identity(model)
        rx, tx = self.rx_pdos(model), self.tx_pdos(model)
        slot_name, modules = self.slot(model)

        def named(pdos: tuple[Pdo, ...]) -> tuple[Pdo, ...]:
            return tuple(self.named_pdo(p) for p in pdos)

        return SlaveDescription(
            device_id=model.device_id, name=self.name, vendor_id=vendor, product_code=product,
            revision=revision, serial=serial, group=self.group, order_code=self.order_code,
            mailbox=(MAILBOX_OUT, MAILBOX_SIZE, MAILBOX_IN, MAILBOX_SIZE),
            coe_details=self.coe_details,
            sync_managers=sync_managers(image.byte_size(rx), image.byte_size(tx)),
            rx_pdos=named(rx), tx_pdos=named(tx), dc_supported=self.dc_supported,
            dc_default=self.dc_default, sm_mode_desc=self.sm_mode_desc,
            pdos_fixed=self.mapping_fixed,
            spare_rx_pdos=named(self.spare_pdos(model, True)),
            spare_tx_pdos=named(self.spare_pdos(model, False)), slot_name=slot_name,
            slot_modules=modules, station_alias=self.station_alias(model),
            vendor_name=self.vendor_name, profile_no=self.profile_no(model),
            diag_texts=self.diag_texts(), **self.modular())

    def profile_no(self, model: Any) -> int:
        """The CoE profile (0x1000 low word) for the ESI Profile; 0 while no dictionary."""
        od = self.od(model)
        return od.peek(0x1000, 0) & 0xFFFF if od is not None and (0x1000, 0) in od else 0

    def diag_texts(self) -> tuple[DiagText, ...]:
        """The texts of the Text-IDs the slave's 0x10F3 carries (ESI DiagMessages)."""
        return ()

    def ready(self, model: Any) -> bool:
        """Whether the model has its dictionary (a description now is the one a master gets)."""
        return not model.reachable() or self.od(model) is not None

    # ---- process data ----------------------------------------------------------------------
    def inputs(self, model: Any) -> bytes:
        """The SM3 image; empty while the model has no dictionary."""
        od = self.od(model)
        if od is None:
            return b""
        found = self.layout(model, False)
        return image.pack_fields(found.fields, found.size, od.peek)

    def apply_outputs(self, model: Any, data: bytes) -> None:
        """The SM2 image the master wrote: each changed object written as an SDO would."""
        od = self.od(model)
        if od is None:
            return
        found = self.layout(model, True)
        if found.size != len(data):
            logger.info("%s: outputs image of %d bytes, the mapping has %d: ignored",
                        model.device_id, len(data), found.size)
            return
        key = id(model)
        wanted = image.changed(found.pdos, self._last_outputs.get(key), data)
        self._last_outputs[key] = bytes(data)
        for index, sub, value in image.unpack_fields(found.fields, data, od.entry):
            if (index, sub) in wanted:
                self.write_output(model, index, sub, value)

    def write_output(self, model: Any, index: int, sub: int, value: int) -> None:
        try:
            self.download(model, index, sub, value)
        except SdoAbort as exc:
            logger.info("%s: output not applied: %s", model.device_id, exc)

    # ---- ESM and mailbox ------------------------------------------------------------------
    def request_state(self, model: Any, state: AlState, ack: bool = False) -> None:
        """AL control: the model accepts or refuses (with its own AL status code); ``ack`` is
        bit 4, "Error Ind Ack" (ETG.1000.6, devices/esm.py Esm.take_request)."""
        model.request_state(state, ack)

    def request_id(self, model: Any, on: bool) -> None:
        """AL control bit 5, ID request (ETG.1000.6): only a slave with an Explicit Device ID
        answers it, in its AL status (ETG.1020); the others ignore the bit."""

    def station_alias(self, model: Any) -> int | None:
        """The configured station alias the slave sets (SII word 4, register 0x0012); 0 = none;
        None: it sets none, the alias stored in SII word 4 stays (the CPX-E-EC at switch 0)."""
        return 0

    def power_ups(self, model: Any) -> int:
        """How often the slave started: each start is an ESC power-up, which loads 0x0012 from
        SII word 4 (only a slave with a station alias of its own needs it)."""
        return 0

    def request_unknown_state(self, model: Any, value: int, ack: bool) -> None:
        """An AL control value whose bits 0-3 name no ESM state (``ack``: bit 4): the model's
        ESM answers it (devices/esm.py ``Esm.request_unknown``: 0x0012, or ignored over the
        error flag without the acknowledge); the model's ``request_state`` takes states only."""
        if model.reachable():
            model.esm.request_unknown(value, ack, model.now_us)

    def configure_dc(self, model: Any, settings: dict[str, int]) -> bool:
        """The master's DC registers (0x0981 activation, 0x09A0 SYNC0 cycle, 0x0990 start
        time) for a model that runs on SYNC0; False when the model takes no DC settings."""
        configure = getattr(model, "configure_dc", None)
        if configure is None:
            return False
        configure(**settings)
        return True

    def configure_sync_managers(self, model: Any, setups: Sequence[SmSetup]) -> bool:
        """The SM registers the master wrote, for a model that checks them; False when the
        model takes none."""
        configure = getattr(model, "configure_sync_managers", None)
        if configure is None or not model.reachable():
            return False
        configure(setups)
        return True

    def al_status(self, model: Any) -> tuple[int, int]:
        return int(model.al_status), int(model.al_status_code)

    def take_emergencies(self, model: Any) -> list[bytes]:
        return list(model.take_emergencies())

    def reachable(self, model: Any) -> bool:
        return bool(model.reachable())

