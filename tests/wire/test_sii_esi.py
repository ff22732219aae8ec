"""ESI XML export (ETG.2000 layout) from the same SlaveDescription as the SII image.

A configurator matches a slave by Vendor Id + Type ProductCode / RevisionNo and builds its
process image from Sm / RxPdo / TxPdo: those must say what the wire shows.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import replace

from test_esc import description

from app.ethercat_wire import esi, sii
from app.ethercat_wire.description import Pdo, PdoEntry


def parsed(desc) -> ET.Element:
    return ET.fromstring(ET.tostring(esi.document(desc).getroot()))


def test_identity_and_name():
    root = parsed(description(3))
    assert root.findtext("Vendor/Id") == "#x00000ABC"
    dev = root.find("Descriptions/Devices/Device")
    typ = dev.find("Type")
    assert (typ.get("ProductCode"), typ.get("RevisionNo"), typ.text) == (
        "#x00000103", "#x00020001", "T-3")
    assert dev.findtext("Name") == "Slave 3"
    assert dev.findtext("GroupType") == root.findtext("Descriptions/Groups/Group/Type") == "Test"


def test_sync_managers_and_fmmus():
    dev = parsed(description(0)).find("Descriptions/Devices/Device")
    sms = [(s.text, s.get("StartAddress"), s.get("ControlByte"), s.get("DefaultSize"))
           for s in dev.findall("Sm")]
    assert sms == [("MBoxOut", "#x1000", "#x26", "128"), ("MBoxIn", "#x1080", "#x22", "128"),
                   ("Outputs", "#x1100", "#x64", "2"), ("Inputs", "#x1180", "#x20", "4")]
    assert [f.text for f in dev.findall("Fmmu")] == ["Outputs", "Inputs", "MBoxState"]


def test_pdos_with_entries_and_data_types():
    dev = parsed(description(0)).find("Descriptions/Devices/Device")
    rx, tx = dev.find("RxPdo"), dev.find("TxPdo")
    assert (rx.get("Sm"), rx.findtext("Index"), tx.get("Sm"), tx.findtext("Index")) == (
        "2", "#x1600", "3", "#x1A00")
    entry = tx.find("Entry")
    assert [entry.findtext(t) for t in ("Index", "SubIndex", "BitLen", "DataType")] == [
        "#x6000", "1", "32", "UDINT"]


def test_mailbox_coe_flags_dc_and_eeprom():
    desc = replace(description(0), coe_details=0x0B)  # SDO, SDO info, PDO config
    dev = parsed(desc).find("Descriptions/Devices/Device")
    coe = dev.find("Mailbox/CoE")
    assert (coe.get("SdoInfo"), coe.get("PdoAssign"), coe.get("PdoConfig")) == (
        "true", "false", "true")
    assert [m.findtext("AssignActivate") for m in dev.findall("Dc/OpMode")] == [
        "#x0000", "#x0300"]
    image = sii.build(desc)
    assert dev.findtext("Eeprom/ByteSize") == str(len(image))
    assert bytes.fromhex(dev.findtext("Eeprom/ConfigData")) == image[:14]


def test_no_mailbox_no_dc():
    dev = parsed(replace(description(0), mailbox=None, dc_supported=False)).find(
        "Descriptions/Devices/Device")
    assert dev.find("Mailbox") is None and dev.find("Dc") is None
    assert [f.text for f in dev.findall("Fmmu")] == ["Outputs", "Inputs"]


def test_files_one_per_slave(tmp_path):
    paths = esi.write([description(0), replace(description(1), name="A/B c")], tmp_path)
    assert [p.name for p in paths] == ["FieldRig_Slave_0.xml", "FieldRig_A_B_c.xml"]
    assert ET.parse(paths[1]).getroot().findtext("Descriptions/Devices/Device/Name") == "A/B c"


def test_static_esi_files_are_those_of_the_default_rig(tmp_path):
    """static/esi/ is what `python -m app ethercat export-esi` writes for the default rig; after
    a change of the default rig's line, run that command again."""
    from pathlib import Path

    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec

    shipped = Path(__file__).resolve().parents[2] / "static" / "esi"
    fresh = esi.write(esi.rig_descriptions(build_rig(load_rig_spec(DEFAULT_RIG))), tmp_path)
    assert sorted(p.name for p in shipped.glob("*.xml")) == sorted(p.name for p in fresh)
    for path in fresh:
        assert (shipped / path.name).read_bytes() == path.read_bytes(), (
            f"static/esi/{path.name} is stale: python -m app ethercat export-esi")


def test_spare_pdos_without_sm_and_fixed_from_the_description():
    """ETG.2000: a PDO without Sm is one the master may assign; Fixed = content not editable."""
    spare = Pdo(0x1601, "Spare", (PdoEntry(0x7000, 2, 8, "Byte out"),))
    desc = replace(description(0), pdos_fixed=False, spare_rx_pdos=(spare,))
    dev = parsed(desc).find("Descriptions/Devices/Device")
    assert [(p.findtext("Index"), p.get("Sm"), p.get("Fixed")) for p in dev.findall("RxPdo")] == [
        ("#x1600", "2", "0"), ("#x1601", None, "0")]
    assert [p.get("Fixed") for p in parsed(description(0)).findall(".//TxPdo")] == ["1"]
