"""The CPX-E-EC on the wire (seed 002): its images in the order of the addressing rules.

Tab. 27 has one TxPDO 0x1A00 + xx / RxPDO 0x1600 + xx per module xx (0 = the bus module) but
no assignment objects. This face puts the PDOs in the order of §2.3.1: the bus module first,
then the analog and technology modules, then the digital ones, each group by ascending module
number; a digital module starts a byte (§2.3.1 "byte-oriented"), so a gap entry pads the one
before it (none of the catalog's modules needs one). The status bits keep their mapped 16 bits
(8 used + 8 unused, Tab. 28 note 4), as the 64-byte budget counts them. The wire answers
0x1C00 and read-only 0x1C12 / 0x1C13 listing those PDOs in that order: a master reads them
(SOEM's config_map fails on the missing 0x1C00, and pysoem reports the SDO error) and sizes
SM2 / SM3 from them, the same sizes as the SII PDOs of the description. Object access goes
through the model's ``cmd_read_object`` / ``cmd_write_object`` (reading a 0x10F3 message marks
it read).
"""

from __future__ import annotations

from typing import Any, ClassVar

from app.ethercat_wire.description import Pdo, PdoEntry
from app.ethercat_wire.faces import image
from app.ethercat_wire.faces.base import RX_ASSIGN, Face, NoAnswer, assignment_objects
from devices.cpx import objects
from devices.cpx.addressing import GROUP_ORDER
from devices.cpx.catalog import ModuleKind
from devices.device import CommandError
from devices.od import ObjectDictionary

RXPDO_BASE, TXPDO_BASE = 0x1600, 0x1A00


class CpxFace(Face):
    kind = "cpx_e_ec"
    name = objects.DEVICE_NAME  # Tab. 27 "CPX-E-EC"
    group = "CPX-E"
    order_code = "CPX-E-EC"
    dc_supported = True  # §2.1.4 Distributed Clocks
    identity_defaults: ClassVar[tuple[int, int, int]] = (
        objects.VENDOR_ID, objects.PRODUCT_CODE, objects.REVISION)

    def __init__(self) -> None:
        super().__init__()
        self._assignment: tuple[Any, ObjectDictionary] | None = None

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

    def request_id(self, model: Any, on: bool) -> None:
        model.request_id(on)  # seed 002 Tab. 5: the Explicit Device ID (devices/cpx/device_id.py)

    def station_alias(self, model: Any) -> int:
        return int(model.station_alias)

    def wire_objects(self, model: Any) -> ObjectDictionary | None:
        od = self.od(model)
        if od is None or (RX_ASSIGN, 0) in od:
            return None
        key = (id(od), tuple(p.index for p in self.rx_pdos(model)),
               tuple(p.index for p in self.tx_pdos(model)))
        if self._assignment is None or self._assignment[0] != key:
            self._assignment = (key, assignment_objects(key[1], key[2]))
        return self._assignment[1]

    def read_pdos(self, model: Any, assign_index: int) -> tuple[Pdo, ...]:
        if (assign_index, 0) in (self.od(model) or ()):
            return super().read_pdos(model, assign_index)
        return self._address_order(model, RXPDO_BASE if assign_index == RX_ASSIGN
                                   else TXPDO_BASE)

    def _address_order(self, model: Any, base: int) -> tuple[Pdo, ...]:
        od = self.od(model)
        if od is None:
            return ()
        out: list[Pdo] = []
        bits = 0
        for kind in GROUP_ORDER:
            for unit in model.units:
                index = base + unit.number
                if unit.mtype.kind is not kind or (index, 0) not in od:
                    continue
                if kind is ModuleKind.DIGITAL and bits % 8 and out:
                    gap = PdoEntry(0, 0, 8 - bits % 8, "")
                    out[-1] = Pdo(out[-1].index, out[-1].name, (*out[-1].entries, gap))
                    bits += gap.bits
                pdo = image.read_pdo(od.peek, od.entry, index)
                out.append(pdo)
                bits += sum(e.bits for e in pdo.entries)
        return tuple(out)
