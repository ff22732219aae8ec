"""The servo drive's CoE slave on the wire (seed 004 ch. 5): the drive model's own mailbox.

SDOs go through the slave's ``sdo_upload`` / ``sdo_download`` (its panel logs them, the
drive's length rule of ch. 4 applies; INIT or off the line: no mailbox, the master times out).
The images are the slave's: ``read_inputs`` packs the TxPDOs assigned in 0x1C13 (None below
SAFEOP), ``write_outputs`` takes the RxPDOs of 0x1C12, applied at the next frame in OP.
For the ESI the face also names the PDOs as the seed's TwinCAT screen does, lists the ones not
assigned and the slot's modules (docs/ethercat-coe.md §ESI file).
"""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any, ClassVar

from app.ethercat_wire.description import Pdo, PdoEntry, SlotModule
from app.ethercat_wire.faces import image
from app.ethercat_wire.faces.base import (
    COE_PDO_ASSIGN,
    COE_PDO_CONFIG,
    COE_SDO,
    COE_SDO_INFO,
    Face,
    NoAnswer,
)
from devices.canopen.comm_objects import RECORD_NAMES
from devices.coe import assignment, objects
from devices.coe.mailbox import MailboxClosed
from devices.device import CommandError

logger = logging.getLogger(__name__)
SLOT_NAME = "Selema Drive"  # ch. 5 Slots tab: the slot the modules go in


class DriveFace(Face):
    kind = "servo_ecat"
    name = "SelemaDriveECAT"  # ch. 5: TwinCAT shows 'Drive 5 (SelemaDriveECAT)'
    group = "Selema Device"  # ch. 5 TwinCAT device tree: Selema > Selema Device
    vendor_name = "Selema"  # ch. 5: the catalogue's vendor folder above "Selema Device"
    order_code = "SelemaDriveECAT"
    dc_supported = True  # ch. 5 "Distributed Clock"
    # ch. 5 "Settaggi SM / DC": TwinCAT's DC tab offers it as "SM-Synchron" (l. 4620, 4645)
    sm_mode_desc = "SM-Synchron"
    coe_details = COE_SDO | COE_SDO_INFO | COE_PDO_ASSIGN | COE_PDO_CONFIG  # ch. 5 dynamic PDOs
    mapping_fixed = False  # 0x1C12 / 0x1C13 and 0x160x / 0x1A0x are written in PREOP (ch. 5)
    identity_defaults: ClassVar[tuple[int, int, int]] = (
        objects.VENDOR_ID, objects.PRODUCT_CODE, objects.REVISION)

    def od(self, model: Any) -> Any:
        return model.dictionary

    def spare_pdos(self, model: Any, receive: bool) -> tuple[Pdo, ...]:
        """The default PDOs 0x1C12 / 0x1C13 do not list now (ch. 5: 8 PDOs, any assignable)."""
        od = self.od(model)
        first = assignment.RX_MAP_FIRST if receive else assignment.TX_MAP_FIRST
        used = {p.index for p in (self.rx_pdos(model) if receive else self.tx_pdos(model))}
        return tuple(image.read_pdo(od.peek, od.entry, index)
                     for index in range(first, first + assignment.PDOS_PER_DIRECTION)
                     if index not in used)

    def pdo_name(self, pdo: Pdo) -> str:
        return assignment.pdo_name(pdo.index)

    def pdo_entry_name(self, entry: PdoEntry) -> str:
        return assignment.pdo_entry_name(entry.index, entry.sub, entry.name)

    def object_name(self, index: int, sub0_name: str) -> str:
        """The drive's dictionary is the CANopen one (ch. 5: "l'unica differenza ... 0x603F"),
        whose records name sub 0 as a count: the object's name is the EDS's."""
        return RECORD_NAMES.get(index, sub0_name)

    def slot(self, model: Any) -> tuple[str, tuple[SlotModule, ...]]:
        """Ch. 5 "Utilizzo degli Slots": one slot, the three modules of TwinCAT's Slots tab,
        each assigning its PDOs; ModuleIdent = the mode's 0x6060 value. A module's PDOs are
        named as TwinCAT's tree shows the Velocity Mode's ("Velocity Inputs / Outputs")."""
        od = self.od(model)
        modules = []
        for s in assignment.XML_SLOTS:
            label = s.module.removesuffix(" Mode")
            rx = replace(self.named_pdo(image.read_pdo(od.peek, od.entry, s.rx)),
                         name=f"{label} Outputs")
            tx = replace(self.named_pdo(image.read_pdo(od.peek, od.entry, s.tx)),
                         name=f"{label} Inputs")
            modules.append(SlotModule(s.mode, s.module, s.description, (rx,), (tx,),
                                      default=s.name == assignment.DEFAULT_SLOT))
        return SLOT_NAME, tuple(modules)

    def upload_raw(self, model: Any, index: int, sub: int) -> bytes:
        try:
            return model.sdo_upload(index, sub)
        except MailboxClosed as exc:
            raise NoAnswer(str(exc)) from None

    def download_raw(self, model: Any, index: int, sub: int, data: bytes) -> None:
        try:
            model.sdo_download(index, sub, data)
        except MailboxClosed as exc:
            raise NoAnswer(str(exc)) from None

    def inputs(self, model: Any) -> bytes:
        return model.read_inputs() or b""

    def apply_outputs(self, model: Any, data: bytes) -> None:
        try:
            model.write_outputs(data)
        except CommandError as exc:
            logger.info("%s: %s", model.device_id, exc)
