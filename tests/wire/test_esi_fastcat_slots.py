"""The FastCAT's ESI as a modular device: 16 slots, the 20 modules of the catalog (seed 000).

§3 (TwinCAT 2): after the line scan «nella tabella degli Slots verrà indicata la lista dei
moduli di I/O rilevati»; §4 (Sirio, LogicLab, no scan): «nella pagina degli slots definire la
composizione del modulo ... i 16 slot disponibili ... i vari moduli che possono andare a comporre
il dispositivo», the PDOs «creati automaticamente durante la definizione degli slot» (0x1AFF
the coupler, 0x1A00 the first module, 0x1A01 the second ...). Both build the image from the
ESI's Slots / Modules, so the ESI has them (docs/fastcat-coupler.md "ESI: slots and modules").
ETG.2000: a module's PDO indices grow by SlotPdoIncrement per slot, its objects by
SlotIndexIncrement (§5: 0x1600 / 0x1A00 + (n - 1); §6: base + 0x10 * (n - 1)).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest
from test_fastcat_pdo_names import configured, coupler, hex_value

from app.ethercat_wire import esi, faces
from devices.fastcat.catalog import CATALOG


def root_of(fc) -> ET.Element:
    return ET.fromstring(ET.tostring(esi.document(faces.describe(fc)).getroot()))


@pytest.fixture(scope="module")
def sirio():
    return coupler(["DB16", "AI8D", "AI8C"])  # the §4 example


@pytest.fixture(scope="module")
def root(sirio) -> ET.Element:
    return root_of(sirio)


def rows(pdos: list[ET.Element]) -> list[tuple[int, list[tuple]]]:
    return [(hex_value(p.findtext("Index")),
             [(hex_value(e.findtext("Index")), int(e.findtext("SubIndex") or 0),
               int(e.findtext("BitLen")), e.findtext("Name"), e.findtext("DataType"))
              for e in p.findall("Entry")]) for p in pdos]


def wire_rows(pdos) -> list[tuple[int, list[tuple]]]:
    """The coupler's PDOs as the ESI writes an entry (a gap: length only; a type by length)."""
    return [(p.index, [(e.index, e.sub, e.bits, e.name, e.data_type or esi.DATA_TYPES[e.bits])
                       if e.index else (0, 0, e.bits, None, None) for e in p.entries])
            for p in pdos]


def test_sixteen_slots_take_any_module_of_the_catalog(root):
    slots = root.find("Descriptions/Devices/Device/Slots")
    assert slots is not None
    assert (slots.get("SlotPdoIncrement"), slots.get("SlotIndexIncrement")) == ("1", "#x10")
    assert slots.get("DownloadModuleIdentList") == "1"  # 0xF030, checked at PREOP -> SAFEOP
    (slot,) = slots.findall("Slot")
    assert (slot.get("MinInstances"), slot.get("MaxInstances")) == ("0", "16")
    assert [m.text for m in slot.findall("ModuleIdent")] == [
        esi.hexid(t.product_code) for t in CATALOG.values()]


def test_one_module_per_catalog_type(root):
    modules = root.findall("Descriptions/Modules/Module")
    assert [(m.find("Type").get("ModuleIdent"), m.findtext("Type"), m.findtext("Name"))
            for m in modules] == [(esi.hexid(t.product_code), t.name, t.description)
                                  for t in CATALOG.values()]
    di16 = next(m for m in modules if m.findtext("Type") == "DI16")
    assert di16.find("RxPdo") is None  # inputs only: no empty output PDO


def test_the_device_lists_the_couplers_own_pdos_only(root):
    device = root.find("Descriptions/Devices/Device")
    assert [p.findtext("Index") for p in device.findall("RxPdo")] == ["#x16FF"]
    assert [p.findtext("Index") for p in device.findall("TxPdo")] == ["#x1AFF"]


@pytest.mark.parametrize("modules", [["DB16", "AI8D", "AI8C"], ["DO16", "AO4", "AX2", "DI16"],
                                     ["AB4M4", "AI8TC", "DO82", "AO4H", "AB4P4"]])
def test_slots_filled_with_the_detected_modules_give_the_wires_pdos(modules):
    """§3: TwinCAT fills the slots from the scan (0xF050, the modules' codes); the PDOs it
    builds from the ESI are those the coupler generated (§5), entry for entry."""
    fc = coupler(modules)
    desc = faces.describe(fc)
    idents = [fc.od.peek(0xF050, n) for n in range(1, len(modules) + 1)]
    root = root_of(fc)
    assert rows(configured(root, idents, "RxPdo")) == wire_rows(desc.rx_pdos)
    assert rows(configured(root, idents, "TxPdo")) == wire_rows(desc.tx_pdos)
