"""The drive's ESI (seed 004 ch. 5): the eight configurable PDOs and the three slots.

Ch. 5 "PDO": "Attivi in totale 8 PDO di cui 4 in trasmissione e 4 in ricezione", the master
may re-assign them (0x1C12 / 0x1C13) and edit their content (0x1600..0x1603, 0x1A00..0x1A03);
"File descrittore .XML": "una mappatura di default, comunque riconfigurabile dal Master"; the
TwinCAT Process Data screen names 0x1A02 "TxPDO 3" and 0x1600 "RxPDO 1".
"""

from __future__ import annotations

import struct
import xml.etree.ElementTree as ET

import pytest

from app.ethercat_wire import esi, sii
from app.rig_config import build_rig, parse_rig_spec

DRIVE_ONLY = """
[rig]
name = "esi-drive"
seed = 1
step_ms = 1
[master]
line = ["drive_ecat-ecat"]
[[servo]]
id = "drive_ecat"
fieldbus = "ethercat"
node_id = 2
"""


@pytest.fixture(scope="module")
def root() -> ET.Element:
    (desc,) = esi.rig_descriptions(build_rig(parse_rig_spec(DRIVE_ONLY)))
    return ET.fromstring(ET.tostring(esi.document(desc).getroot()))


@pytest.fixture(scope="module")
def device(root) -> ET.Element:
    return root.find("Descriptions/Devices/Device")


def pdo_rows(parent: ET.Element, tag: str) -> list[tuple[str, str, str | None, str | None]]:
    return [(p.findtext("Index"), p.findtext("Name"), p.get("Sm"), p.get("Fixed"))
            for p in parent.findall(tag)]


def test_all_eight_pdos_named_as_twincat_shows_sm_only_on_the_default_ones(device):
    assert pdo_rows(device, "RxPdo") == [
        ("#x1600", "RxPDO 1", "2", "0"), ("#x1601", "RxPDO 2", None, "0"),
        ("#x1602", "RxPDO 3", None, "0"), ("#x1603", "RxPDO 4", None, "0")]
    assert pdo_rows(device, "TxPdo") == [
        ("#x1A02", "TxPDO 3", "3", "0"), ("#x1A00", "TxPDO 1", None, "0"),
        ("#x1A01", "TxPDO 2", None, "0"), ("#x1A03", "TxPDO 4", None, "0")]


def test_unassigned_pdos_carry_their_ch5_contents(device):
    contents = {p.findtext("Index"): [(e.findtext("Index"), e.findtext("SubIndex"),
                                       e.findtext("BitLen")) for e in p.findall("Entry")]
                for p in (*device.findall("RxPdo"), *device.findall("TxPdo"))}
    assert contents["#x1601"] == [("#x6040", "0", "16"), ("#x6060", "0", "8")]
    assert contents["#x1603"] == [("#x6040", "0", "16"), ("#x60FF", "0", "32")]
    assert contents["#x1A01"] == [("#x6041", "0", "16"), ("#x6061", "0", "8")]
    assert contents["#x1A03"] == [("#x6041", "0", "16"), ("#x606C", "0", "32")]


def test_the_default_pdos_size_the_process_data_sync_managers(device):
    """SM2 / SM3 DefaultSize stay those of the assigned PDOs only (6 + 6 bytes)."""
    sizes = {s.text: s.get("DefaultSize") for s in device.findall("Sm")}
    assert (sizes["Outputs"], sizes["Inputs"]) == ("6", "6")


def test_one_slot_offers_the_three_seed_modules_interpolated_by_default(root):
    """Ch. 5 "Utilizzo degli Slots": three mutually exclusive slots; "Di default sarà impostata
    la modalità Interpolated Mode". CSP (0x6060 = 8) is no slot of the seed's."""
    slots = root.find("Descriptions/Devices/Device/Slots")
    assert slots is not None and slots.get("DownloadModuleIdentList") == "0"  # no 0xF030
    (slot,) = slots.findall("Slot")
    assert (slot.get("MinInstances"), slot.get("MaxInstances")) == ("1", "1")
    idents = [(m.text, m.get("Default")) for m in slot.findall("ModuleIdent")]
    assert idents == [("#x00000001", None), ("#x00000007", "1"), ("#x00000003", None)]
    modules = {m.find("Type").get("ModuleIdent"): m
               for m in root.findall("Descriptions/Modules/Module")}
    assert sorted(modules) == sorted(i for i, _ in idents)
    rows = [(modules[i].findtext("Type"), modules[i].findtext("Name")) for i, _ in idents]
    assert rows == [("Position Mode", "Position Mode"),
                    ("Interpolated Mode", "Profile Interpolated Mode"),
                    ("Velocity Mode", "Profile Velocity Mode")]


@pytest.mark.parametrize(("ident", "rx", "tx", "label"), [
    ("#x00000001", "#x1602", "#x1A02", "Position"),
    ("#x00000007", "#x1600", "#x1A02", "Interpolated"),
    ("#x00000003", "#x1603", "#x1A03", "Velocity")])
def test_each_module_assigns_its_slots_pdos(root, device, ident, rx, tx, label):
    """The slot's PDOs of ch. 5, assigned to SM2 / SM3 when the module is in the slot; named
    as TwinCAT's tree shows the Velocity Mode module: 'Velocity Inputs' / 'Velocity Outputs'."""
    (module,) = [m for m in root.findall("Descriptions/Modules/Module")
                 if m.find("Type").get("ModuleIdent") == ident]
    assert pdo_rows(module, "RxPdo") == [(rx, f"{label} Outputs", "2", "0")]
    assert pdo_rows(module, "TxPdo") == [(tx, f"{label} Inputs", "3", "0")]
    same = {p.findtext("Index"): [ET.tostring(e) for e in p.findall("Entry")]
            for p in (*device.findall("RxPdo"), *device.findall("TxPdo"))}
    for pdo in (*module.findall("RxPdo"), *module.findall("TxPdo")):
        assert [ET.tostring(e) for e in pdo.findall("Entry")] == same[pdo.findtext("Index")]


def entry_rows(pdo: ET.Element) -> list[tuple[str | None, str | None, str | None]]:
    return [(e.findtext("Index"), e.findtext("Name"), e.findtext("DataType"))
            for e in pdo.findall("Entry")]


def test_default_tx_pdo_entries_named_and_typed_as_the_process_data_screen(device):
    """Ch. 5 "Cambio configurazione PDO con Twincat", PDO Content (0x1A02): "604100 Status Word
    UINT", "606400 Position Actual Value DINT": the .xml's names and types, signed included."""
    (pdo,) = [p for p in device.findall("TxPdo") if p.findtext("Index") == "#x1A02"]
    assert entry_rows(pdo) == [("#x6041", "Status Word", "UINT"),
                               ("#x6064", "Position Actual Value", "DINT")]


def test_velocity_module_entries_named_as_the_twincat_tree(root):
    """Ch. 5 "Dispositivi I/O" tree: Module 1 (Velocity Mode) > Velocity Inputs: Status Word,
    Actual Velocity; Velocity Outputs: Control Word, Target Velocity (0x606C / 0x60FF are
    INTEGER32: DINT)."""
    (module,) = [m for m in root.findall("Descriptions/Modules/Module")
                 if m.find("Type").get("ModuleIdent") == "#x00000003"]
    assert entry_rows(module.find("TxPdo")) == [("#x6041", "Status Word", "UINT"),
                                                ("#x606C", "Actual Velocity", "DINT")]
    assert entry_rows(module.find("RxPdo")) == [("#x6040", "Control Word", "UINT"),
                                                ("#x60FF", "Target Velocity", "DINT")]


def test_other_entries_named_as_the_ch5_pdo_list(device):
    """Ch. 5 "PDO": Set-Point Position (0x60C1:1), Modes of Operation (0x6060), Target Position
    (0x607A), Modes of Operation Display (0x6061); 0x6060 / 0x6061 are INTEGER8: SINT."""
    rows = {p.findtext("Index"): entry_rows(p)
            for p in (*device.findall("RxPdo"), *device.findall("TxPdo"))}
    assert rows["#x1600"][1] == ("#x60C1", "Set-Point Position", "DINT")
    assert rows["#x1601"][1] == ("#x6060", "Modes of Operation", "SINT")
    assert rows["#x1602"][1] == ("#x607A", "Target Position", "DINT")
    assert rows["#x1A01"][1] == ("#x6061", "Modes of Operation Display", "SINT")


def test_sii_pdo_entries_carry_the_same_names_and_types():
    """The SII TXPDO category of the drive: 0x6064 with ETG data type 0x0004 (DINT) and the
    .xml's entry name, as a master that reads the SII (no CoE mapping) shows it."""
    (desc,) = esi.rig_descriptions(build_rig(parse_rig_spec(DRIVE_ONLY)))
    image = sii.build(desc)
    data = sii.categories(image)[sii.CAT_TXPDO][0]
    names = sii.strings(image)
    entries = [struct.unpack_from("<HBBBBH", data, 8 + 8 * n) for n in range(data[2])]
    assert [(i, names[name - 1], dtype) for i, _, name, dtype, _, _ in entries] == [
        (0x6041, "Status Word", 0x06), (0x6064, "Position Actual Value", 0x04)]
