"""The default rig's ESI files against the seeds: what each seed says of its slave's ESI / SII.

Seed 000 (FastCAT) §6.5, seed 001 (TRS-CAT) §9 / §9.1.1, seed 002 (CPX-E-EC) Tab. 27 /
§2.1.4, seed 004 (drive) ch. 5. What the seeds leave open is FieldRig's (docs/ethercat-wire.md
"SII and ESI from the same description").
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import pytest

from app.ethercat_wire import esi, sii
from app.ethercat_wire.description import SlaveDescription
from app.ethercat_wire.faces import face_for
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec


@pytest.fixture(scope="module")
def rig() -> Any:
    return build_rig(load_rig_spec(DEFAULT_RIG))


@pytest.fixture(scope="module")
def line(rig) -> dict[str, SlaveDescription]:
    return {d.name: d for d in esi.rig_descriptions(rig)}


def device(desc: SlaveDescription) -> ET.Element:
    root = ET.fromstring(ET.tostring(esi.document(desc).getroot()))
    return root.find("Descriptions/Devices/Device")


@pytest.mark.parametrize(("name", "vendor", "product"), [
    ("FastCAT", "#x000000C6", "#x0000FACA"),  # seed 000 §6.5
    ("CPX-E-EC", "#x0000001D", None),  # seed 002 Tab. 27 (no product code printed)
    ("SelemaDriveECAT", "#x0000078F", None),  # seed 004 ch. 5 "Vendor ID ... 0x0000078F"
])
def test_identity_the_seeds_print(line, name, vendor, product):
    desc = line[name]
    root = ET.fromstring(ET.tostring(esi.document(desc).getroot()))
    assert root.findtext("Vendor/Id") == vendor
    if product is not None:
        assert root.find("Descriptions/Devices/Device/Type").get("ProductCode") == product
    image = sii.build(desc)
    assert int.from_bytes(image[0x10:0x14], "little") == int(vendor[2:], 16)
    assert int.from_bytes(image[0x14:0x18], "little") == desc.product_code


def test_trscat_sync_managers_and_fmmus_as_section_9(line):
    """§9: SM0 Mailbox Out, SM1 Mailbox In, SM2 Process Output, SM3 Process Input; 3 FMMUs
    Outputs, Inputs, Mailbox State."""
    dev = device(line["TRS-CAT"])
    assert [s.text for s in dev.findall("Sm")] == ["MBoxOut", "MBoxIn", "Outputs", "Inputs"]
    assert [f.text for f in dev.findall("Fmmu")] == ["Outputs", "Inputs", "MBoxState"]


def test_trscat_lists_dc_sync_first_its_default_mode(line):
    """§9.1.1: "I modi di sincronizzazione supportati sono il DC-SYNC e il FREE-RUN" and DC-SYNC
    "è quella di default", register 0x0980 = 0x0300. A configurator takes the first OpMode of
    the ESI as the slave's default."""
    modes = [(m.findtext("Name"), m.findtext("AssignActivate"))
             for m in device(line["TRS-CAT"]).findall("Dc/OpMode")]
    assert modes == [("DC", "#x0300"), ("FreeRun", "#x0000")]


@pytest.mark.parametrize("name", ["CPX-E-EC", "SelemaDriveECAT"])
def test_free_run_first_where_the_seed_names_no_default(line, name):
    """Seed 002 §2.1.4 says only that DC is supported; seed 004 ch. 5 recommends SM-Synchron,
    the mode its TwinCAT screen shows selected."""
    modes = [m.findtext("Name") for m in device(line[name]).findall("Dc/OpMode")]
    assert modes == ["FreeRun", "DC"]


def test_drive_offers_sm_synchron_as_its_twincat_screen_names_it(line):
    """Seed 004 ch. 5 "Settaggi SM / DC" (l. 4613-4658): "impostare ... la sincronizzazione SM -
    Synchron. Vedi figura seguente nel caso specifico di twincat", and the DC tab's drop-down
    reads "Moda operativa: SM-Synchron" (l. 4620, 4645) next to DC-Synchron. A configurator
    lists the OpModes by their Desc: the drive's must read SM-Synchron, not FreeRun/SM-Synchron."""
    modes = [m.findtext("Desc") for m in device(line["SelemaDriveECAT"]).findall("Dc/OpMode")]
    assert modes == ["SM-Synchron", "DC-Synchron"]


def test_fastcat_has_no_dc(line):
    """Seed 000 names no distributed clock: no Dc element, nor DC in the ESC's features."""
    assert device(line["FastCAT"]).find("Dc") is None
    assert not line["FastCAT"].dc_supported


@pytest.mark.parametrize("kind", ["trscat", "cpx_e_ec", "servo_ecat"])
def test_entries_typed_as_their_objects(rig, line, kind):
    """Seeds 001 / 002 print no PDO entry types: the ESI gives each mapped object's own type,
    signed where the object is (the drive's seed shows it so: "Position Actual Value DINT")."""
    model = {link.slave.KIND: link.slave for link in rig.devices["master"].links}[kind]
    face = face_for(model)
    od = face.od(model)
    entries = [e for p in device(line[face.name]).iter() if p.tag in ("RxPdo", "TxPdo")
               for e in p.findall("Entry") if e.findtext("Index") != "#x0000"]
    assert entries
    for e in entries:
        obj = od.entry(int(e.findtext("Index")[2:], 16), int(e.findtext("SubIndex")))
        assert e.findtext("DataType") == obj.dtype.short, e.findtext("Name")


def test_fastcat_entries_unsigned_by_length_as_its_section_4_screen(line):
    """Seed 000 §4: 0x6420:1 "Analog inp 1" UINT 16, an INT 16 object in §6.25."""
    root = ET.fromstring(ET.tostring(esi.document(line["FastCAT"]).getroot()))
    types = {e.findtext("DataType") for e in root.iter("Entry")  # the modules' included
             if e.findtext("Index") != "#x0000"}
    assert types <= {"BOOL", "USINT", "UINT", "UDINT"} and "UINT" in types


@pytest.mark.parametrize(("name", "vendor"), [
    ("SelemaDriveECAT", "Selema"),  # seed 004 ch. 5: TwinCAT's catalogue "Selema > Selema Device"
    ("CPX-E-EC", "Festo"),  # seed 002, Festo's manual (title page, www.festo.com)
    ("FastCAT", "FastCAT (FieldRig virtual slave)"),  # seed 000 names no vendor
    ("TRS-CAT", "TRS-CAT (FieldRig virtual slave)"),  # seed 001: only "TPA_TRSCAT.xml"
])
def test_vendor_name_the_configurator_files_the_device_under(line, name, vendor):
    root = ET.fromstring(ET.tostring(esi.document(line[name]).getroot()))
    assert root.findtext("Vendor/Name") == vendor


def test_sii_strings_keep_the_names_readable(line):
    """Tab. 27's PDO names have an en dash ("Module xx – TxPDO"), which Latin-1 lacks: the SII
    stores an ASCII hyphen, not a '?'."""
    names = sii.strings(sii.build(line["CPX-E-EC"]))
    assert "Module 0 - TxPDO" in names and not [s for s in names if "?" in s]
