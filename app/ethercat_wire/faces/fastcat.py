"""The FastCAT coupler on the wire (seed 000): identity, PDOs and images from its own objects.

The coupler generates its mapping from the modules of the last scan (§5): 0x16FF / 0x1AFF
(Reset fault / Fault active) always, then 0x1600 + (n - 1) / 0x1A00 + (n - 1) for module n,
listed in 0x1C12 / 0x1C13 in that order. The images are those mappings bit for bit
(:mod:`app.ethercat_wire.faces.image`): 0x16FF's Reset fault is bit 0 of SM2, then a 7-bit
gap (§6.17 "2:8 Reserved (7)"), so module 1's outputs start at byte 1. Until a scan has
built the dictionary (power-up, every return to INIT, §3) there is no mapping and no image.
The ESI is a modular device: 16 slots taking any module of the catalog, the Device keeping
0x16FF / 0x1AFF (§3 / §4, docs/fastcat-coupler.md "ESI: slots and modules").
The image's entries are process data, not SDO writes: the coupler takes them in OP only
(``FastCat.write_process_output``).
"""

from __future__ import annotations

import logging
from typing import Any, ClassVar

from app.ethercat_wire.description import Pdo, PdoEntry, SlotModule
from app.ethercat_wire.faces.base import Face
from devices.fastcat import module_od, objects
from devices.fastcat.catalog import CATALOG
from devices.od import SdoAbort

SLOT_NAME = "I/O module"  # §4: the slots page, one slot per module along the internal bus

logger = logging.getLogger(__name__)


class FastCatFace(Face):
    kind = "fastcat"
    name = objects.DEVICE_NAME  # §6.2 "FastCAT"; TwinCAT shows 'Box 1 (FastCAT)' (§7.1)
    group = "FastCAT"
    order_code = "FastCAT"
    dc_supported = False  # seed 000 names no distributed clock
    identity_defaults: ClassVar[tuple[int, int, int]] = (
        objects.VENDOR_ID, objects.PRODUCT_CODE, objects.REVISION)

    def write_output(self, model: Any, index: int, sub: int, value: int) -> None:
        try:
            model.write_process_output(index, sub, value)
        except SdoAbort as exc:
            logger.info("%s: output not applied: %s", model.device_id, exc)

    def pdo_entry_name(self, entry: PdoEntry) -> str:
        """§4's screen: 0x6420:1 is "Analog inp 1" in the PDO, "Analog input 1" in §6.25."""
        return module_od.pdo_entry_name(entry.index, entry.sub, entry.name)

    def pdo_entry_type(self, entry: PdoEntry) -> str:
        """Unsigned by bit length: §4's screen types 0x6420:1, an INT 16 of §6.25, "UINT"."""
        return ""

    def pdo_mandatory(self, pdo: Pdo) -> bool:
        """§4's screen ticks Mandatory for 0x1AFF; §5 has 0x16FF / 0x1AFF always present."""
        return pdo.index in (objects.COUPLER_RXPDO, objects.COUPLER_TXPDO)

    def slot(self, model: Any) -> tuple[str, tuple[SlotModule, ...]]:
        """§3 / §4: the configurator fills the 16 slots (from the scan, or by hand on Sirio)
        with modules of the catalog; each module brings its PDOs as module 1 (0x1600 / 0x1A00,
        objects at their §6 base), moved per slot by the increments of :meth:`modular`."""
        modules = []
        for mtype in CATALOG.values():
            od = objects.catalog_objects(mtype)
            modules.append(SlotModule(mtype.product_code, mtype.name, mtype.description,
                                      self.module_pdo(od, objects.RXPDO_BASE),
                                      self.module_pdo(od, objects.TXPDO_BASE)))
        return SLOT_NAME, tuple(modules)

    def modular(self) -> dict[str, Any]:
        """§4 «i 16 slot disponibili»; §5 PDO 0x1600 / 0x1A00 + (n - 1), §6 objects at base +
        0x10 * (n - 1); the ESI's Device keeps 0x16FF / 0x1AFF, the coupler's own (§5); the
        coupler compares a written 0xF030 with 0xF050 (§7.5 row 0x14)."""
        return {"slot_count": objects.MAX_MODULES, "slot_pdo_increment": 1,
                "slot_index_increment": module_od.MODULE_STRIDE,
                "device_pdos": frozenset({objects.COUPLER_RXPDO, objects.COUPLER_TXPDO}),
                "download_module_idents": True}
