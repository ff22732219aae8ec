"""The FastCAT's PDOs as a configurator lists them: seed 000 §4, the "Slave settings" screen.

With a DB16, an AI8D and an AI8C the screen lists 0x1AFF "Status" (Fixed, Mandatory), 0x1A00
"Inputs", 0x1A01 and 0x1A02 "Analog inputs", and 0x6420:1..8 "Analog inp 1".."Analog inp 8",
UINT 16 bit. The coupler's own mapping objects carry those PDO names (SDO Information gives
them); the entry names are the ESI's / SII's, the objects keep their §6 names ("Analog input
1", §6.25). The others are named in the same style (docs/fastcat-coupler.md).
"""

from __future__ import annotations

import copy
import random
import xml.etree.ElementTree as ET

import pytest

from app.ethercat_wire import esi, faces
from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash

STEP_US = 1_000


def coupler(modules: list[str]) -> FastCat:
    fc = FastCat("fastcat", random.Random(1), [(m, {}) for m in modules], flash=MemoryFlash())
    fc.apply("power", {"on": True}, None)
    now = 0
    while fc.od is None or now < 500_000:
        now += STEP_US
        fc.step(now)
        assert now < 20_000_000, "no dictionary after the scan"
    return fc


@pytest.fixture(scope="module")
def sirio() -> FastCat:
    return coupler(["DB16", "AI8D", "AI8C"])  # the §4 example


def hex_value(text: str) -> int:
    return int(text[2:], 16) if text.startswith("#x") else int(text)


def configured(root: ET.Element, idents: list[int], tag: str) -> list[ET.Element]:
    """The PDOs a configurator builds from the ESI with module ``idents[k]`` in slot k
    (ETG.2000): the device's own, then each module's, its PDO index + k * SlotPdoIncrement,
    its entries' indices + k * SlotIndexIncrement (docs/fastcat-coupler.md). Only an Index
    marked DependOnSlot moves: a configurator leaves an unmarked one where the ESI says."""
    device = root.find("Descriptions/Devices/Device")
    slots = device.find("Slots")
    pdo_step = hex_value(slots.get("SlotPdoIncrement"))
    index_step = hex_value(slots.get("SlotIndexIncrement"))
    modules = {hex_value(m.find("Type").get("ModuleIdent")): m
               for m in root.findall("Descriptions/Modules/Module")}
    out = list(device.findall(tag))
    for k, ident in enumerate(idents):
        for pdo in modules[ident].findall(tag):
            pdo = copy.deepcopy(pdo)
            moved(pdo.find("Index"), k * pdo_step)
            for index in pdo.findall("Entry/Index"):
                moved(index, k * index_step)
            out.append(pdo)
    return out


def moved(index: ET.Element, offset: int) -> None:
    """ETG.2000: an Index with DependOnSlot moves by the slot's increment, another stays."""
    if index.get("DependOnSlot") in ("1", "true"):
        index.text = esi.hexid(hex_value(index.text or "0") + offset, 4)


class Screen:
    """The slave as the configurator shows it after the scan (§3): the slots filled with
    the modules 0xF050 reports."""

    def __init__(self, fc: FastCat) -> None:
        self.root = ET.fromstring(ET.tostring(esi.document(faces.describe(fc)).getroot()))
        count = fc.od.peek(0xF050, 0)
        self.idents = [fc.od.peek(0xF050, n) for n in range(1, count + 1)]
        self.device = self.root.find("Descriptions/Devices/Device")

    def findall(self, tag: str) -> list[ET.Element]:
        if tag in ("RxPdo", "TxPdo"):
            return configured(self.root, self.idents, tag)
        return self.device.findall(tag)


def device(fc: FastCat) -> Screen:
    return Screen(fc)


def test_tx_pdos_as_the_section_4_screen(sirio):
    rows = [(p.findtext("Index"), p.findtext("Name"), p.get("Sm"), p.get("Fixed"),
             p.get("Mandatory", "0")) for p in device(sirio).findall("TxPdo")]
    assert rows == [("#x1AFF", "Status", "3", "1", "1"),
                    ("#x1A00", "Inputs", "3", "1", "0"),
                    ("#x1A01", "Analog inputs", "3", "1", "0"),
                    ("#x1A02", "Analog inputs", "3", "1", "0")]


def test_analog_entries_as_the_section_4_screen(sirio):
    pdo = next(p for p in device(sirio).findall("TxPdo") if p.findtext("Index") == "#x1A02")
    entries = [tuple(e.findtext(t) for t in ("Index", "SubIndex", "Name", "DataType", "BitLen"))
               for e in pdo.findall("Entry")]
    assert entries == [("#x6420", str(k), f"Analog inp {k}", "UINT", "16") for k in range(1, 9)]


def test_the_objects_keep_their_section_6_names(sirio):
    """The OD is §6's: 0x6420:1 is "Analog input 1" (§6.25), INT 16; the mapping objects are
    named as the PDOs they are (SDO Information names an object by its sub 0)."""
    od = sirio.od
    assert od.entry(0x6420, 1).name == "Analog input 1"
    assert od.entry(0x6420, 1).dtype.name == "INTEGER16"
    assert [od.entry(i, 0).name for i in (0x1AFF, 0x1A00, 0x1A01, 0x1A02)] == [
        "Status", "Inputs", "Analog inputs", "Analog inputs"]
    assert [od.entry(i, 0).name for i in (0x16FF, 0x1600, 0x1601)] == [
        "Control", "Outputs", "Analog outputs"]


def test_the_others_in_the_same_style():
    """Outputs, analog outputs, encoders; 0x16FF is mandatory like 0x1AFF (§5: always there)."""
    dev = device(coupler(["DO16", "AO4", "AX2", "DI16"]))
    rx = [(p.findtext("Index"), p.findtext("Name"), p.get("Mandatory", "0"),
           p.find("Entry/Name").text) for p in dev.findall("RxPdo")]
    assert rx == [("#x16FF", "Control", "1", "Reset fault"),
                  ("#x1600", "Outputs", "0", "Digital out 1"),
                  ("#x1601", "Analog outputs", "0", "Analog out 1"),
                  ("#x1602", "Encoder outputs", "0", "Operating parameters")]
    tx = [(p.findtext("Index"), p.findtext("Name"), p.find("Entry/Name").text)
          for p in dev.findall("TxPdo")]
    assert tx == [("#x1AFF", "Status", "Fault active"),
                  ("#x1A02", "Encoder inputs", "Position encoder 1"),
                  ("#x1A03", "Inputs", "Digital inp 1")]
