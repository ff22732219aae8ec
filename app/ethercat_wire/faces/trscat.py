"""The TRS-CAT on the wire (seed 001 §9): MDP slots from 0xF030, sync managers, CoE.

The PDO assignment 0x1C12 / 0x1C13 follows the slot list the master writes to 0xF030 in
PRE-OP (§9.3.2), so the images are re-read from the dictionary every time: a master that
writes 0xF030 and then reads the mapping (``config_map``) gets the image the device will use.
Object access goes through the model's ``read_object`` / ``write_object`` (the write refreshes
the device, e.g. the PDO list after 0xF030). The ESI is a modular device: the integrated module
fixed in the first slot, the expansions after it, DownloadModuleIdentList so a configurator
writes 0xF030 itself (§9.2 PS, §9.3.2, §9.3.3; docs/trscat.md "ESI: slots and modules").
"""

from __future__ import annotations

from typing import Any, ClassVar

from app.ethercat_wire.description import SlotGroup, SlotModule
from app.ethercat_wire.faces.base import (
    COE_COMPLETE_ACCESS,
    COE_SDO,
    COE_SDO_INFO,
    Face,
    NoAnswer,
)
from devices.device import CommandError
from devices.trscat import objects, pdo
from devices.trscat.catalog import BY_IDENT, MAX_SLOTS, ident_allowed_at

# the slots by the first 0xF030 sub they cover (§9.3.2: sub 1 integrated, sub 8 expansion 7)
SLOT_NAMES = {1: "Integrated module", 8: "Expansion 7"}


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

    def slot(self, model: Any) -> tuple[str, tuple[SlotModule, ...]]:
        """§9.3.3: each module (the integrated one too) one RxPDO and one TxPDO; the catalogue
        entry of each kind is its PDOs in the first slot (0x1600 / 0x1A00, objects 0x7000 /
        0x6000), moved per slot by the increments of :meth:`modular`."""
        modules = []
        for kind in BY_IDENT.values():
            od = pdo.catalog_objects(kind)
            modules.append(SlotModule(
                kind.ident, kind.name,
                f"{kind.name} ({kind.short}): {kind.inputs} inputs, {kind.outputs} outputs",
                self.module_pdo(od, pdo.RXPDO_BASE), self.module_pdo(od, pdo.TXPDO_BASE),
                default=kind.integrated))
        return "", tuple(modules)

    def modular(self) -> dict[str, Any]:
        """§9.3.2: 0xF030 sub 1 the integrated module only, subs 2..7 any expansion, sub 8 no
        smart one: the slots, grouped where they take the same modules (the device's own
        rule, ``ident_allowed_at``); §9.3.3 PDO 0x1600 / 0x1A00 + slot, objects + 0x10 per
        slot (0xF000:1); the Device keeps 0x1AFF; the master writes 0xF030 in PS (§9.2)."""
        return {"slot_groups": slot_groups(), "slot_count": MAX_SLOTS, "slot_pdo_increment": 1,
                "slot_index_increment": pdo.INDEX_DISTANCE,
                "device_pdos": frozenset({pdo.DEVICE_TXPDO}), "download_module_idents": True}


def slot_groups() -> tuple[SlotGroup, ...]:
    """0xF030 subs 1..8 in runs of the same allowed idents (§9.3.2's tables)."""
    runs: list[tuple[int, tuple[int, ...], int]] = []  # first sub, idents, slots
    for sub in range(1, MAX_SLOTS + 1):
        idents = tuple(i for i in BY_IDENT if ident_allowed_at(sub, i))
        if runs and runs[-1][1] == idents:
            runs[-1] = (runs[-1][0], idents, runs[-1][2] + 1)
        else:
            runs.append((sub, idents, 1))
    return tuple(SlotGroup(SLOT_NAMES.get(first, "Expansion"), 1 if first == 1 else 0, count,
                           idents, idents[0] if first == 1 else 0)
                 for first, idents, count in runs)
