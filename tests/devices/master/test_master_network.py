"""Network description and mapping files (seed 003 ¶1-2): parsing, generation, rig errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.network.generate import generate
from app.rig_config import RigConfigError, build_rig, load_rig_spec
from devices.master.network import NetworkFileError, parse_eni, parse_mapping

ROOT = Path(__file__).resolve().parents[3]
LINE_RIG = ROOT / "static" / "rigs" / "ethercat_line.toml"
NETWORKS = ROOT / "static" / "networks"

SMALL_ENI = """<?xml version="1.0"?>
<EtherCATConfig><Config>
  <Slave><Info><Name>Box 1 (FastCAT)</Name><Device>fastcat</Device><PhysAddr>#x3E9</PhysAddr>
    <VendorId>198</VendorId><ProductCode>#xFACA</ProductCode><RevisionNo>#x10007</RevisionNo>
  </Info></Slave>
  <Slave><Info><Name>TRS</Name><Device>trscat</Device><PhysAddr>2000</PhysAddr>
    <VendorId>1</VendorId><ProductCode>2</ProductCode><RevisionNo>3</RevisionNo></Info>
    <Mailbox><CoE><InitCmds><InitCmd><Transition>PS</Transition><Comment>list</Comment>
      <Index>#xF030</Index><SubIndex>0</SubIndex><Data>02</Data></InitCmd></InitCmds></CoE>
    </Mailbox><DC><Use>true</Use></DC></Slave>
</Config></EtherCATConfig>"""


def test_small_description() -> None:
    fc, trs = parse_eni(SMALL_ENI)
    assert (fc.position, fc.device, fc.station_address, fc.vendor, fc.product, fc.revision,
            fc.dc) == (0, "fastcat", 1001, 0xC6, 0xFACA, 0x10007, False)
    assert (trs.station_address, trs.dc) == (2000, True)
    assert [(c.transition, c.index, c.sub, c.data) for c in trs.commands("PS")] == [
        ("PS", 0xF030, 0, b"\x02")]


@pytest.mark.parametrize(("text", "element"), [
    ("<!DOCTYPE x [<!ENTITY a 'b'>]><EtherCATConfig/>", ""),
    ("<EtherCATConfig><Config>", ""),
    ("<Other/>", "Other"),
    ("<EtherCATConfig><Config><Slave><Info><Name>a</Name></Info></Slave></Config>"
     "</EtherCATConfig>", "Config/Slave[0]/Info"),
    (SMALL_ENI.replace("<PhysAddr>2000", "<PhysAddr>1001"), "Config/Slave[1]/Info/PhysAddr"),
    (SMALL_ENI.replace("<Transition>PS", "<Transition>XX"),
     "Config/Slave[1]/Mailbox/CoE/InitCmds/InitCmd[0]/Transition"),
    (SMALL_ENI.replace("<Data>02", "<Data>zz"),
     "Config/Slave[1]/Mailbox/CoE/InitCmds/InitCmd[0]/Data"),
    (SMALL_ENI.replace("<VendorId>198", "<VendorId>lots"), "Config/Slave[0]/Info/VendorId"),
])
def test_bad_descriptions_name_the_element(text: str, element: str) -> None:
    with pytest.raises(NetworkFileError) as info:
        parse_eni(text)
    assert info.value.element == element


def test_entities_are_never_expanded() -> None:
    """A billion-laughs file is refused before the XML parser sees it."""
    bomb = '<?xml version="1.0"?><!DOCTYPE l [<!ENTITY a "aaaa">]><MasterConfig>&a;' \
           '</MasterConfig>'
    with pytest.raises(NetworkFileError, match="DOCTYPE"):
        parse_mapping(bomb)


def test_mapping_parameters_and_variables() -> None:
    m = parse_mapping('<MasterConfig><Parameters><CycleTimeUs>2000</CycleTimeUs>'
                      '<DcSyncWindowNs>500</DcSyncWindowNs></Parameters><Variables>'
                      '<Variable Name="in1" Slave="1" Index="#x6000" SubIndex="1" BitLen="1" '
                      'Direction="input"/></Variables></MasterConfig>')
    assert (m.parameters.cycle_us, m.parameters.dc_window_ns) == (2000, 500)
    assert [(v.name, v.position, v.index, v.sub, v.bit_length, v.direction)
            for v in m.variables] == [("in1", 1, 0x6000, 1, 1, "input")]


@pytest.mark.parametrize("name", ["ethercat_line", "default"])
def test_committed_files_are_what_the_generator_makes(name: str) -> None:
    """static/networks/*: regenerate with python -m app.network.generate --all."""
    rig = ROOT / "static" / "rigs" / f"{name}.toml"
    if "trscat" not in load_rig_spec(rig).line:
        pytest.skip(f"{rig.name} is not the full line yet")
    text = "\n".join(line for line in rig.read_text().splitlines()
                     if not line.startswith(("eni =", "mapping =")))
    eni, mapping = generate(text, f"static/rigs/{name}.toml")
    assert eni == (NETWORKS / f"{name}.eni.xml").read_text()
    assert mapping == (NETWORKS / f"{name}.mapping.xml").read_text()


def test_generated_description_of_the_line() -> None:
    """Identity from each model's 0x1018; 0xF030 written in PS (seed 001 §9.2, seed 002
    Text-ID 0x3801), then the CPX-E-EC's 0x10F3:5 (seed 002 Tab. 14); DC for the TRS-CAT in
    DC-SYNC and the CPX-E-EC with 16DI / 8DO."""
    slaves = parse_eni((NETWORKS / "ethercat_line.eni.xml").read_text())
    rig = build_rig(load_rig_spec(LINE_RIG))
    assert [s.device for s in slaves] == ["fastcat", "trscat", "cpx", "drive_ec-ecat"]
    assert [s.station_address for s in slaves] == [1001, 1002, 1003, 1004]
    assert [s.dc for s in slaves] == [False, True, True, False]
    cpx = rig.devices["cpx"]
    assert (slaves[2].vendor, slaves[2].product, slaves[2].revision) == tuple(
        cpx.od.peek(0x1018, sub) for sub in (1, 2, 3))
    trs = slaves[1].commands("PS")
    assert [(c.index, c.sub) for c in trs] == [(0xF030, s) for s in range(4)]
    assert trs[0].data == b"\x03"  # integrated module + 2 expansions
    assert trs[1].data == (0x494F2D42).to_bytes(4, "little")  # "IO-B" (§9.3.2)
    cmds = slaves[2].commands("PS")
    assert cmds[0].data == len(cpx.units).to_bytes(2, "little")
    assert [int.from_bytes(c.data, "little") for c in cmds[1:-1]] == [
        u.mtype.ident for u in cpx.units]
    # the rig's history_flags = 1 after the list (seed 002 Tab. 14: 0x0000 until written)
    assert [(c.index, c.sub, c.data) for c in cmds[-1:]] == [(0x10F3, 5, b"\x01\x00")]
    master = rig.devices["master"]
    assert master.mapping is not None and master.mapping.parameters.cycle_us == 1000
    assert {v.position for v in master.mapping.variables} == {0, 1, 2, 3}


def _rig_with(tmp_path: Path, eni: str | None = None, mapping: str | None = None) -> Path:
    text = LINE_RIG.read_text()
    text = "\n".join(line for line in text.splitlines()
                     if not line.startswith(("eni =", "mapping =", "flash =")))
    keys = []
    if eni is not None:
        (tmp_path / "net.eni.xml").write_text(eni)
        keys.append('eni = "net.eni.xml"')
    if mapping is not None:
        (tmp_path / "net.mapping.xml").write_text(mapping)
        keys.append('mapping = "net.mapping.xml"')
    text = text.replace("[master]\n", "[master]\n" + "\n".join(keys) + "\n")
    rig = tmp_path / "rig.toml"
    rig.write_text(text)
    return rig


def test_a_slave_not_on_the_line_is_a_rig_error(tmp_path: Path) -> None:
    eni = (NETWORKS / "ethercat_line.eni.xml").read_text().replace(
        "<Device>cpx</Device>", "<Device>cpx9</Device>")
    with pytest.raises(RigConfigError) as info:
        build_rig(load_rig_spec(_rig_with(tmp_path, eni)))
    assert info.value.source.endswith("net.eni.xml")
    assert info.value.key == "Config/Slave[2]/Info/Device"
    assert "'cpx9' is not a slave on the line" in info.value.reason


def test_bad_xml_is_a_rig_error_with_the_file(tmp_path: Path) -> None:
    with pytest.raises(RigConfigError, match=r"net\.mapping\.xml.*not well-formed"):
        build_rig(load_rig_spec(_rig_with(tmp_path, mapping="<MasterConfig>")))


def test_mapping_naming_a_missing_position(tmp_path: Path) -> None:
    mapping = ('<MasterConfig><Variables><Variable Name="x" Slave="7" Index="1" SubIndex="1" '
               'BitLen="1" Direction="input"/></Variables></MasterConfig>')
    with pytest.raises(RigConfigError) as info:
        build_rig(load_rig_spec(_rig_with(tmp_path, mapping=mapping)))
    assert info.value.key == "Variables/Variable[0]@Slave"


def test_user_selected_station_addresses(tmp_path: Path) -> None:
    """Seed 003: the physical address can be chosen by the user in the configuration."""
    eni = (NETWORKS / "ethercat_line.eni.xml").read_text().replace(
        "<PhysAddr>1003</PhysAddr>", "<PhysAddr>300</PhysAddr>")
    rig = build_rig(load_rig_spec(_rig_with(tmp_path, eni)))
    master = rig.devices["master"]
    assert master.slave_by_address(300)["device"] == "cpx"
    assert rig.devices["cpx"].station_address == 300


def test_the_fastcat_s_variables_are_its_mapped_entries() -> None:
    """Seed 000 §4: a PLC variable per PDO entry, 0x1AFF's coupler inputs first; §6.16 /
    §6.17: Fault active and Reset fault are process data (§7: the reset is raised through
    the exchanged data); §6.27 / §6.30: the AX2's status and command words (sub 0) are in
    its TxPDO / RxPDO. Before, only 0x6000-0x7FFF entries with a sub > 0 got one."""
    mapping = parse_mapping((NETWORKS / "default.mapping.xml").read_text())
    fastcat = {(v.index, v.sub, v.bit_length, v.direction)
               for v in mapping.variables if v.position == 0}
    ax2 = 7  # default.toml: the AX2 is module 7
    assert {(0x5100, 1, 1, "input"), (0x5200, 1, 1, "output"),
            (0x6600 + 0x10 * (ax2 - 1), 0, 16, "input"),
            (0x7600 + 0x10 * (ax2 - 1), 0, 16, "output")} <= fastcat
    assert not any(index == 0 for index, *_rest in fastcat)  # the 7-bit gaps are no variable
