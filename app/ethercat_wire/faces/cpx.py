"""The CPX-E-EC on the wire (seed 002): its images in the order of the addressing rules.

Tab. 27 has one TxPDO 0x1A00 + xx / RxPDO 0x1600 + xx per module xx (0 = the bus module); the
model assigns them in 0x1C12 / 0x1C13 in the order of §2.3.1 (devices/cpx/assignment.py) and a
master may add 0x1A40 (New Message Available, 0x10F3:4) to 0x1C13 in PREOP. The status bits
keep their mapped 16 bits (8 used + 8 unused, Tab. 28 note 4). The wire answers 0x1C00 (SOEM's
config_map needs it) and sizes SM2 / SM3 from the assignment; the ESI lists 0x1A40 without Sm
while it is not assigned. Object access goes through the model's ``cmd_read_object`` /
``cmd_write_object`` (reading a 0x10F3 message marks it read).
"""

from __future__ import annotations

from typing import Any, ClassVar

from app.ethercat_wire.description import LCID_ENGLISH, LCID_RUSSIAN, DiagText, Pdo
from app.ethercat_wire.faces import image
from app.ethercat_wire.faces.base import (
    COE_PDO_ASSIGN,
    COE_SDO,
    COE_SDO_INFO,
    TX_ASSIGN,
    Face,
    Layout,
    NoAnswer,
)
from devices.cpx import codes, objects
from devices.cpx.assignment import DIAG_PDO
from devices.device import CommandError


class CpxFace(Face):
    kind = "cpx_e_ec"
    name = objects.DEVICE_NAME  # Tab. 27 "CPX-E-EC"
    group = "CPX-E"
    vendor_name = "Festo"  # seed 002 is Festo's manual (title page; www.festo.com for the ESI)
    order_code = "CPX-E-EC"
    dc_supported = True  # §2.1.4 Distributed Clocks
    # 0x1C13 is written in PREOP (0x1A40, seed 002 l. 539-541): SII GENERAL / ESI PdoAssign.
    # No PdoConfig: the mappings are fixed (Tab. 27, sub 0 RO).
    coe_details = COE_SDO | COE_SDO_INFO | COE_PDO_ASSIGN
    identity_defaults: ClassVar[tuple[int, int, int]] = (
        objects.VENDOR_ID, objects.PRODUCT_CODE, objects.REVISION)

    def upload(self, model: Any, index: int, sub: int) -> Any:
        try:
            return model.cmd_read_object(index, sub)
        except CommandError as exc:
            raise NoAnswer(str(exc)) from None

    def download(self, model: Any, index: int, sub: int, value: Any) -> None:
        try:
            model.cmd_write_object(index, sub, value)
        except CommandError as exc:
            raise NoAnswer(str(exc)) from None

    def bootstrap_mailbox(self, model: Any) -> bool:
        return bool(model.bootstrap_mailbox())  # BOOT: firmware download only (choice 47)

    def diag_texts(self) -> tuple[DiagText, ...]:
        """§2.5.2: «Диагностические события транслируются с помощью файла ESI» — each Text-ID
        the history carries, with the texts of the model's table (choice 48)."""
        return tuple(
            DiagText(text_id, ((LCID_ENGLISH, english),) +
                     (((LCID_RUSSIAN, russian),) if russian else ()))
            for text_id, (russian, english) in sorted(codes.text_id_texts().items()))

    def request_id(self, model: Any, on: bool) -> None:
        model.request_id(on)  # seed 002 Tab. 5: the Explicit Device ID (devices/cpx/device_id.py)

    def al_status(self, model: Any) -> tuple[int, int]:
        """With the ID loaded, AL status bit 0x20 and the ID at 0x0134 (devices/cpx/device_id.py);
        the model's al_status_code stays its ESM's error code."""
        status, code = model.al_status_on_wire()
        return int(status), int(code)

    def station_alias(self, model: Any) -> int | None:
        alias = model.station_alias  # None: switches at 0, the stored alias (Tab. 5)
        return None if alias is None else int(alias)

    def power_ups(self, model: Any) -> int:
        return int(model.power_ups)

    def layout(self, model: Any, receive: bool) -> Layout:
        """As the base, but 0x1C13 changes in PREOP (0x1A40, devices/cpx/assignment.py):
        re-read when the assignment differs from the cached layout's."""
        found = super().layout(model, receive)
        od = self.od(model)
        if receive or od is None or (TX_ASSIGN, 0) not in od:
            return found
        if tuple(p.index for p in found.pdos) != tuple(image.assigned(od.peek, TX_ASSIGN)):
            self._layouts.pop((id(model), False), None)
            found = super().layout(model, receive)
        return found

    def spare_pdos(self, model: Any, receive: bool) -> tuple[Pdo, ...]:
        """0x1A40 (New Message Available) when not assigned: the ESI lists it without Sm."""
        od = self.od(model)
        if receive or od is None or (DIAG_PDO, 0) not in od or \
                DIAG_PDO in image.assigned(od.peek, TX_ASSIGN):
            return ()
        return (image.read_pdo(od.peek, od.entry, DIAG_PDO),)
