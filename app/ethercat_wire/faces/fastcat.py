"""The FastCAT coupler on the wire (seed 000): identity, PDOs and images from its own objects.

The coupler generates its mapping from the modules of the last scan (§5): 0x16FF / 0x1AFF
(Reset fault / Fault active) always, then 0x1600 + (n - 1) / 0x1A00 + (n - 1) for module n,
listed in 0x1C12 / 0x1C13 in that order. The images are those mappings bit for bit
(:mod:`app.ethercat_wire.faces.image`): 0x16FF's Reset fault is bit 0 of SM2, then a 7-bit
gap (§6.17 "2:8 Reserved (7)"), so module 1's outputs start at byte 1. Until a scan has
built the dictionary (power-up, every return to INIT, §3) there is no mapping and no image.
"""

from __future__ import annotations

from typing import ClassVar

from app.ethercat_wire.description import Pdo, PdoEntry
from app.ethercat_wire.faces.base import Face
from devices.fastcat import module_od, objects


class FastCatFace(Face):
    kind = "fastcat"
    name = objects.DEVICE_NAME  # §6.2 "FastCAT"; TwinCAT shows 'Box 1 (FastCAT)' (§7.1)
    group = "FastCAT"
    order_code = "FastCAT"
    dc_supported = False  # seed 000 names no distributed clock
    identity_defaults: ClassVar[tuple[int, int, int]] = (
        objects.VENDOR_ID, objects.PRODUCT_CODE, objects.REVISION)

    def pdo_entry_name(self, entry: PdoEntry) -> str:
        """§4's screen: 0x6420:1 is "Analog inp 1" in the PDO, "Analog input 1" in §6.25."""
        return module_od.pdo_entry_name(entry.index, entry.sub, entry.name)

    def pdo_entry_type(self, entry: PdoEntry) -> str:
        """Unsigned by bit length: §4's screen types 0x6420:1, an INT 16 of §6.25, "UINT"."""
        return ""

    def pdo_mandatory(self, pdo: Pdo) -> bool:
        """§4's screen ticks Mandatory for 0x1AFF; §5 has 0x16FF / 0x1AFF always present."""
        return pdo.index in (objects.COUPLER_RXPDO, objects.COUPLER_TXPDO)
