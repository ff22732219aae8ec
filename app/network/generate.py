"""Write the network description (ENI-like) and the mapping file of a rig's EtherCAT line.

What an EtherCAT configurator does from the slaves' ESI files, done from the models: identity
from each model's 0x1018 constants, station addresses 1001.. in line order, DC use per model
(TRS-CAT in DC-SYNC, seed 001 §9.1.1; CPX-E-EC with a DC-capable module, seed 002 §2.1.4),
init commands written as CoE SDO downloads (the TRS-CAT's 0xF030 list in PS, the rig's
``configured`` or else the expansions it has, seed 001 §9.2 / §9.3.2; the CPX-E-EC's 0xF030 in
PS, seed 002 Tab. 17 Text-ID 0x3801, and its rig ``history_flags`` as 0x10F3:5 in PS, Tab. 14)
and one PLC variable per PDO entry.
``python -m app.network.generate RIG OUT_PREFIX`` writes OUT_PREFIX.eni.xml and
OUT_PREFIX.mapping.xml (``--all`` regenerates the files under static/networks/).
"""

from __future__ import annotations

import argparse
import struct
import sys
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape

from app.network.files import uses_dc
from app.network.startup import MODULE_LIST, f030_commands, trscat_list_commands
from app.rig import Rig
from app.rig_config import build_rig, load_rig_spec, parse_rig_spec
from devices.canopen.pdo import split_entry
from devices.master.network import InitCmd, SlaveDescription, Variable

ROOT = Path(__file__).resolve().parents[2]
NETWORKS = ROOT / "static" / "networks"
CYCLE_US = 1000
DC_WINDOW_NS = 1000


def _identity(kind: str) -> tuple[int, int, int]:
    if kind == "fastcat":
        from devices.fastcat import objects as o
    elif kind == "trscat":
        from devices.trscat import objects as o  # type: ignore[no-redef]
    elif kind == "cpx_e_ec":
        from devices.cpx import objects as o  # type: ignore[no-redef]
    else:
        from devices.coe import objects as o  # type: ignore[no-redef]
    return o.VENDOR_ID, o.PRODUCT_CODE, o.REVISION


def _u16(v: int) -> bytes:
    return struct.pack("<H", v)


def _slave(device: Any, position: int, rig_cmds: tuple[InitCmd, ...]) -> SlaveDescription:
    kind = device.KIND
    vendor, product, revision = _identity(kind)
    cmds: tuple[InitCmd, ...] = ()
    dc = uses_dc(device)
    if kind == "trscat" and not any(c.index == MODULE_LIST for c in rig_cmds):
        from devices.trscat.catalog import INTEGRATED

        # No `configured` list in the rig: the expansions it has, as a configurator scans them.
        cmds = trscat_list_commands([k.ident for k in (INTEGRATED, *device._chain())])
    elif kind == "cpx_e_ec":
        idents = [u.mtype.ident for u in device.units]
        cmds = f030_commands(idents, _u16(len(idents)), "CPX-E-EC")
    return SlaveDescription(position, device.box_name, device.device_id, vendor, product,
                            revision, device.station_address, dc, (*cmds, *rig_cmds))


def describe(rig: Rig) -> list[SlaveDescription]:
    master = rig.devices.get("master")
    if master is None:
        return []
    # The rig's start-up values (app/network/startup.py) ride on the descriptions the rig
    # derived for the master: the TRS-CAT's `configured` list is its 0xF030 list; the others
    # are written after the 0xF030 list, as a Startup tab lists them.
    return [_slave(link.slave, link.position,
                   link.description.init_cmds if link.description is not None else ())
            for link in master.links]  # type: ignore[attr-defined]


def variables(rig: Rig) -> list[Variable]:
    """One PLC variable per entry of the PDOs a slave assigns, as a configurator makes them
    (seed 000 §4: the PLC variables go on the PDO entries): for an object dictionary the
    entries of 0x1C13's and 0x1C12's PDOs, inputs then outputs, each by index; a CoE
    drive's assigned PDOs."""
    master = rig.devices["master"]
    out: list[Variable] = []
    for link in master.links:  # type: ignore[attr-defined]
        slave, pos = link.slave, link.position
        prefix = slave.device_id.replace("-", "_")
        if slave.KIND == "servo_ecat":
            for pdos, direction in ((slave.rx_assigned, "output"), (slave.tx_assigned, "input")):
                for pdo in pdos:
                    for raw in pdo.entries[: pdo.count]:
                        index, sub, bits = split_entry(raw)
                        out.append(Variable(f"{prefix}_{index:04X}_{sub:02X}", pos, index, sub,
                                            bits, direction))
            continue
        od = getattr(slave, "od", None)
        if od is None:
            continue
        for index, sub, bits, direction in _assigned_entries(od):
            out.append(Variable(f"{prefix}_{index:04X}_{sub:02X}", pos, index, sub, bits,
                                direction))
    return out


def _assigned_entries(od: Any) -> list[tuple[int, int, int, str]]:
    """(index, sub, bits, direction) of every entry mapped in the assigned PDOs. The coupler
    bits (0x5100:1, 0x5200:1, seed 000 §6.16 / §6.17) and the single-value objects mapped
    at sub 0 (the AX2's 0x6600 / 0x7600, §6.27 / §6.30) are process data too; a gap (index
    0) is none."""
    out = []
    for assign, direction in ((0x1C13, "input"), (0x1C12, "output")):
        if (assign, 0) not in od:
            continue
        for k in range(1, od.peek(assign, 0) + 1):
            pdo = od.peek(assign, k)
            for j in range(1, od.peek(pdo, 0) + 1):
                index, sub, bits = split_entry(od.peek(pdo, j))
                if index:
                    out.append((index, sub, bits, direction))
    return sorted(out, key=lambda e: (e[3] != "input", e[0], e[1]))


def eni_xml(slaves: list[SlaveDescription], source: str) -> str:
    lines = ['<?xml version="1.0" encoding="utf-8"?>',
             f"<!-- Generated by app/network/generate.py from {escape(source)} -->",
             '<EtherCATConfig Version="1.3">', "  <Config>",
             "    <Master><Info><Name>Device 1 (EtherCAT)</Name></Info></Master>"]
    for s in slaves:
        lines += ["    <Slave>", "      <Info>",
                  f"        <Name>{escape(s.name)}</Name>",
                  f"        <Device>{escape(s.device)}</Device>",
                  f"        <PhysAddr>{s.station_address}</PhysAddr>",
                  f"        <AutoIncAddr>{-s.position & 0xFFFF}</AutoIncAddr>",
                  f"        <VendorId>#x{s.vendor:08X}</VendorId>",
                  f"        <ProductCode>#x{s.product:08X}</ProductCode>",
                  f"        <RevisionNo>#x{s.revision:08X}</RevisionNo>",
                  "      </Info>"]
        if s.init_cmds:
            lines += ["      <Mailbox>", "        <CoE>", "          <InitCmds>"]
            for c in s.init_cmds:
                lines += ["            <InitCmd>",
                          f"              <Transition>{c.transition}</Transition>",
                          f"              <Comment>{escape(c.comment)}</Comment>",
                          f"              <Index>#x{c.index:04X}</Index>",
                          f"              <SubIndex>{c.sub}</SubIndex>",
                          f"              <Data>{c.data.hex()}</Data>",
                          "            </InitCmd>"]
            lines += ["          </InitCmds>", "        </CoE>", "      </Mailbox>"]
        lines.append(f"      <DC><Use>{'true' if s.dc else 'false'}</Use></DC>")
        lines.append("    </Slave>")
    lines += ["  </Config>", "</EtherCATConfig>", ""]
    return "\n".join(lines)


def mapping_xml(variables: list[Variable], source: str, cycle_us: int = CYCLE_US,
                window_ns: int = DC_WINDOW_NS) -> str:
    lines = ['<?xml version="1.0" encoding="utf-8"?>',
             f"<!-- Generated by app/network/generate.py from {escape(source)} -->",
             "<MasterConfig>", "  <Parameters>",
             f"    <CycleTimeUs>{cycle_us}</CycleTimeUs>",
             f"    <DcSyncWindowNs>{window_ns}</DcSyncWindowNs>", "  </Parameters>",
             "  <Variables>"]
    for v in variables:
        lines.append(f'    <Variable Name="{escape(v.name)}" Slave="{v.position}" '
                     f'Index="#x{v.index:04X}" SubIndex="{v.sub}" BitLen="{v.bit_length}" '
                     f'Direction="{v.direction}"/>')
    lines += ["  </Variables>", "</MasterConfig>", ""]
    return "\n".join(lines)


SETTLE_US = 4_000_000  # every dictionary exists (the FastCAT's after its first scan)


def generate(rig_text: str, source: str) -> tuple[str, str]:
    spec = parse_rig_spec(rig_text, source)
    rig = build_rig(spec)
    slaves = describe(rig)  # before running: the line as configured, not as started
    rig.run_until(SETTLE_US)
    return eni_xml(slaves, source), mapping_xml(variables(rig), source)


def write(rig_text: str, source: str, prefix: Path) -> list[Path]:
    eni, mapping = generate(rig_text, source)
    paths = [prefix.with_name(prefix.name + ".eni.xml"),
             prefix.with_name(prefix.name + ".mapping.xml")]
    paths[0].write_text(eni, encoding="utf-8")
    paths[1].write_text(mapping, encoding="utf-8")
    return paths


def _without_network(text: str) -> str:
    """The rig text without its eni / mapping keys (the files are being made from it)."""
    return "\n".join(line for line in text.splitlines()
                     if not line.strip().startswith(("eni =", "mapping =")))


def regenerate_all() -> list[Path]:
    """static/networks/: the line rig's files, and the default rig's (the full line: master ->
    FastCAT -> TRS-CAT -> CPX-E-EC -> the drive on EtherCAT)."""
    out = []
    for rig, prefix in (("ethercat_line.toml", "ethercat_line"), ("default.toml", "default")):
        text = _without_network((ROOT / "static" / "rigs" / rig).read_text(encoding="utf-8"))
        out += write(text, f"static/rigs/{rig}", NETWORKS / prefix)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.network.generate")
    parser.add_argument("rig", nargs="?")
    parser.add_argument("prefix", nargs="?")
    parser.add_argument("--all", action="store_true")
    args = parser.parse_args(argv)
    if args.all:
        paths = regenerate_all()
    elif args.rig and args.prefix:
        spec = load_rig_spec(args.rig)
        text = _without_network(Path(spec.source).read_text(encoding="utf-8"))
        paths = write(text, args.rig, Path(args.prefix))
    else:
        parser.error("give RIG OUT_PREFIX, or --all")
    for path in paths:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
