"""The drive's ESI (seed 004 ch. 5): the eight configurable PDOs and the three slots.

Ch. 5 "PDO": "Attivi in totale 8 PDO di cui 4 in trasmissione e 4 in ricezione", the master
may re-assign them (0x1C12 / 0x1C13) and edit their content (0x1600..0x1603, 0x1A00..0x1A03);
"File descrittore .XML": "una mappatura di default, comunque riconfigurabile dal Master"; the
TwinCAT Process Data screen names 0x1A02 "TxPDO 3" and 0x1600 "RxPDO 1".
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from app.ethercat_wire import esi
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
def device() -> ET.Element:
    (desc,) = esi.rig_descriptions(build_rig(parse_rig_spec(DRIVE_ONLY)))
    root = ET.fromstring(ET.tostring(esi.document(desc).getroot()))
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
