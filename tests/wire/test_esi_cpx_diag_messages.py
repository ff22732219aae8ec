"""The CPX-E-EC's ESI gives the text of every Text-ID its 0x10F3 history carries.

Seed 002 §2.5.2 (l. 452): «Диагностические события транслируются с помощью файла ESI»; Tab. 17
lists the EtherCAT Text-IDs «из ESI-файла» with their Russian and English text, and 0x3700 +
n are the CPX error numbers. ETG.2000: Device / Profile / DiagMessages / DiagMessage (TextId,
MessageText per LcId), Profile between GroupType and Fmmu, DiagMessages after ProfileNo.
The texts come from devices/cpx/codes.py, the one table (docs/cpx-e-ec.md choice 48).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import pytest

from app.ethercat_wire import esi
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from devices.cpx import codes

ENGLISH, RUSSIAN = "1033", "1049"
TAB_17 = (0x3800, 0x3801, 0x000F, 0x0011, 0x0012, 0x0013)


@pytest.fixture(scope="module")
def device(tmp_path_factory: Any) -> ET.Element:
    """The CPX-E-EC's file as written (ISO-8859-1: the Russian travels as references)."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    paths = esi.write(esi.rig_descriptions(rig), tmp_path_factory.mktemp("esi"))
    (path,) = [p for p in paths if p.name == "FieldRig_CPX-E-EC.xml"]
    return ET.parse(path).getroot().find("Descriptions/Devices/Device")


def messages(device: ET.Element) -> dict[str, list[ET.Element]]:
    found: dict[str, list[ET.Element]] = {}
    for m in device.findall("Profile/DiagMessages/DiagMessage"):
        found.setdefault(m.findtext("TextId"), []).append(m)
    return found


def test_every_text_id_of_the_table_once_with_its_texts(device):
    table = codes.text_id_texts()
    assert set(TAB_17) <= set(table) and set(codes.TEXT_IDS) <= set(table)
    found = messages(device)
    assert set(found) == {esi.hexid(t, 4) for t in table}
    for text_id, (russian, english) in table.items():
        (message,) = found[esi.hexid(text_id, 4)]
        texts = {t.get("LcId"): t.text for t in message.findall("MessageText")}
        assert texts == ({ENGLISH: english, RUSSIAN: russian} if russian else
                         {ENGLISH: english})


def test_tab_17_words_as_the_seed_prints_them(device):
    (message,) = messages(device)["#x3801"]
    assert [t.text for t in message.findall("MessageText")] == [
        "Ident check skipped – PLC has not written to Object 0xF030",
        "Проверка идентификации модуля не выполнена – Контроллер не записал объект 0xF030"]


def test_the_history_s_cpx_error_texts(device):
    """0x3700 + n for the CPX error numbers the model reports (2 from Tab. 16)."""
    found = messages(device)
    assert found["#x3702"][0].findtext("MessageText") == "Short circuit/overload"
    assert found["#x3700"][0].findtext("MessageText") == "No error"


def test_element_order_of_etg_2000(device):
    tags = [child.tag for child in device]
    assert tags.index("GroupType") < tags.index("Profile") < tags.index("Fmmu")
    assert [child.tag for child in device.find("Profile")] == ["ProfileNo", "DiagMessages"]
    assert device.findtext("Profile/ProfileNo") == "5001"  # Tab. 27 0x1000: 0x1389, MDP
    for message in device.findall("Profile/DiagMessages/DiagMessage"):
        tags = [c.tag for c in message]
        assert tags[0] == "TextId" and set(tags[1:]) == {"MessageText"}
