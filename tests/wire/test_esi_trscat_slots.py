"""The TRS-CAT's ESI as a modular device: the integrated module, then the expansions (seed 001).

§9.2 PS: the master «Invia la configurazione TRS mediante oggetto 0xF030»; §9.3: «L'unica,
indispensabile configurazione è dunque quella relativa al download della configurazione degli
slot»; §9.3.2: 0xF030 «deve essere inviata dal master a TRS-CAT durante la transizione PS», sub
1 the integrated module («ammesso solo 0x494F2D42»), subs 2..7 any expansion, sub 8 no smart
one; §9.3.3: each module one RxPDO and one TxPDO (0x1600 / 0x1A00 the integrated's), plus the
device's 0x1AFF. A configurator writes 0xF030 itself only from an ESI with Slots and
DownloadModuleIdentList (docs/trscat.md "ESI: slots and modules"); the PDOs it then builds
from the slots are the ones the TRS-CAT assigns after the write, entry for entry.
"""

from __future__ import annotations

import random
import xml.etree.ElementTree as ET

import pytest
from test_esi_fastcat_slots import rows, wire_rows
from test_fastcat_pdo_names import configured, hex_value

from app.ethercat_wire import esi, faces
from devices.ethercat import AlState
from devices.trscat.catalog import BY_IDENT, EXPANSIONS, INTEGRATED, MAX_SLOTS
from devices.trscat.device import TrsCat

STEP_US = 1_000


def preop(expansions: list[str]) -> TrsCat:
    trs = TrsCat("trscat", random.Random(3), expansions)
    trs.apply("power", {"on": True}, None)
    trs.request_state(AlState.PREOP)
    now = 0
    while trs.al_state is not AlState.PREOP:
        now += STEP_US
        trs.step(now)
        assert now < 2_000_000, "no PRE-OP after the detection"
    return trs


def root_of(trs: TrsCat) -> ET.Element:
    return ET.fromstring(ET.tostring(esi.document(faces.describe(trs)).getroot()))


@pytest.fixture(scope="module")
def root() -> ET.Element:
    return root_of(preop(["TRS-IO-E", "TRS-AN-E"]))


def test_slots_download_the_module_list(root):
    slots = root.find("Descriptions/Devices/Device/Slots")
    assert slots is not None
    assert slots.get("DownloadModuleIdentList") == "1"  # 0xF030, checked at PS (§9.2)
    assert (slots.get("SlotPdoIncrement"), slots.get("SlotIndexIncrement")) == ("1", "#x10")


def test_the_integrated_module_is_fixed_in_the_first_slot(root):
    """§9.3.2: sub 1 «ammesso solo 0x494F2D42»; subs 2..7 the five expansions; sub 8
    (expansion 7) no smart one. Eight slots in all (§5)."""
    groups = [(s.get("MinInstances"), s.get("MaxInstances"),
               [(hex_value(m.text), m.get("Default")) for m in s.findall("ModuleIdent")])
              for s in root.findall("Descriptions/Devices/Device/Slots/Slot")]
    every = [(k.ident, None) for k in EXPANSIONS.values()]
    standard = [(k.ident, None) for k in EXPANSIONS.values() if not k.smart]
    assert groups == [("1", "1", [(INTEGRATED.ident, "1")]), ("0", "6", every),
                      ("0", "1", standard)]
    assert sum(int(g[1]) for g in groups) == MAX_SLOTS


def test_one_module_per_kind_the_device_keeps_0x1aff(root):
    modules = root.findall("Descriptions/Modules/Module")
    assert [hex_value(m.find("Type").get("ModuleIdent")) for m in modules] == list(BY_IDENT)
    device = root.find("Descriptions/Devices/Device")
    assert device.findall("RxPdo") == []
    assert [p.findtext("Index") for p in device.findall("TxPdo")] == ["#x1AFF"]


@pytest.mark.parametrize("expansions", [[], ["TRS-IO-E", "TRS-AN-E"],
                                        ["TRS-XX-E", "TRS-AC-E", "TRS-IO-E", "TRS-KK-E"],
                                        ["TRS-AN-E"] * 6 + ["TRS-XX-E"]])
def test_slots_filled_as_detected_give_the_pdos_after_the_download(expansions):
    """TwinCAT fills the slots from the scan (0xF050), writes their idents to 0xF030 in PS
    (DownloadModuleIdentList) and builds the image from the modules; the TRS-CAT assigns its
    PDOs from 0xF030 (§9.3.2 footnote 4): the same, entry for entry."""
    trs = preop(expansions)
    idents = [trs.od.peek(0xF050, n) for n in range(1, trs.od.peek(0xF050, 0) + 1)]
    face = faces.face_for(trs)
    for sub, ident in enumerate(idents, start=1):  # what the configurator downloads
        face.download(trs, 0xF030, sub, ident)
    face.download(trs, 0xF030, 0, len(idents))
    desc, root = faces.describe(trs), root_of(trs)
    assert rows(configured(root, idents, "RxPdo")) == wire_rows(desc.rx_pdos)
    assert rows(configured(root, idents, "TxPdo")) == wire_rows(desc.tx_pdos)
