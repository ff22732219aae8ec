"""The TRS-CAT on the wire (seed 001 §9): MDP slots from 0xF030, sync managers, CoE.

The PDO assignment 0x1C12 / 0x1C13 follows the slot list the master writes to 0xF030 in
PRE-OP (§9.3.2), so the images are re-read from the dictionary every time: a master that
writes 0xF030 and then reads the mapping (``config_map``) gets the image the device will use.
Object access goes through the model's ``read_object`` / ``write_object`` (the write refreshes
the device, e.g. the PDO list after 0xF030).
"""

from __future__ import annotations

from typing import Any, ClassVar

from app.ethercat_wire.faces.base import (
    COE_COMPLETE_ACCESS,
    COE_SDO,
    COE_SDO_INFO,
    Face,
    NoAnswer,
)
from devices.device import CommandError
from devices.trscat import objects


class TrsCatFace(Face):
    kind = "trscat"
    name = objects.DEVICE_NAME  # "TRS-CAT" (ESI TPA_TRSCAT.xml, §9)
    group = "TRS-CAT"
    order_code = "TRS-CAT"
    dc_supported = True  # §9.1.1 DC-SYNC on SYNC0
    dc_default = True  # §9.1.1: DC-SYNC "è quella di default" (0x0980 = 0x0300)
    # §9 / §9.3: "SDO information service con accesso completo e la possibilità di segmentare
    # i frame": complete access announced (SOEM's config_map then reads the mapping with it;
    # docs/ethercat-wire.md "SDO complete access").
    coe_details = COE_SDO | COE_SDO_INFO | COE_COMPLETE_ACCESS
    identity_defaults: ClassVar[tuple[int, int, int]] = (
        objects.VENDOR_ID, objects.PRODUCT_CODE, objects.REVISION)

    def upload(self, model: Any, index: int, sub: int) -> Any:
        try:
            return model.read_object(index, sub)
        except CommandError as exc:
            raise NoAnswer(str(exc)) from None

    def download(self, model: Any, index: int, sub: int, value: Any) -> None:
        try:
            model.write_object(index, sub, value)
        except CommandError as exc:
            raise NoAnswer(str(exc)) from None
