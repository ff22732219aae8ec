"""ESI files (EtherCAT Slave Information, ETG.2000 XML) for the slaves of a rig's line.

Built from the same SlaveDescription as the SII image, so a configurator that imports them
(TwinCAT, CODESYS, IgH `ethercat` tool users, ...) expects exactly what the wire shows:
vendor, Type ProductCode / RevisionNo, Name, Profile (DiagMessages: the texts of the 0x10F3
Text-IDs, where the slave has them), Fmmu, Sm, RxPdo / TxPdo (the assigned ones with
their Sm, the others a master may assign without), Mailbox / CoE, Dc, Slots (+ Descriptions /
Modules: PDO sets a configurator selects, the drive's slots; the FastCAT's 16 slots of
catalog modules), Eeprom. One file per slave of
the line.

    python -m app ethercat export-esi [--rig RIG] [--out static/esi/]
"""

from __future__ import annotations

import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from app.cli_parser import Parser
from app.ethercat_wire import sii
from app.ethercat_wire.description import Pdo, SlaveDescription, SlotGroup

DEFAULT_OUT = Path("static/esi")
BOOT_LIMIT_US = 20_000_000  # a FastCAT scans its modules for seconds after power-up
# ETG data type names by bit length, for an entry the description gives no type of its own
DATA_TYPES = {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT", 64: "ULINT"}
SM_NAMES = {sii.SM_TYPE_MBX_OUT: "MBoxOut", sii.SM_TYPE_MBX_IN: "MBoxIn",
            sii.SM_TYPE_OUTPUTS: "Outputs", sii.SM_TYPE_INPUTS: "Inputs"}
FMMU_NAMES = {sii.FMMU_OUTPUTS: "Outputs", sii.FMMU_INPUTS: "Inputs",
              sii.FMMU_MBX_STATE: "MBoxState"}
COE_FLAGS = (("SdoInfo", 0x02), ("PdoAssign", 0x04), ("PdoConfig", 0x08),
             ("PdoUpload", 0x10), ("CompleteAccess", 0x20))


def hexid(value: int, digits: int = 8) -> str:
    return f"#x{value:0{digits}X}"


def _text(parent: ET.Element, tag: str, text: str, **attrs: str) -> ET.Element:
    el = ET.SubElement(parent, tag, attrs)
    el.text = text
    return el


def _pdo(parent: ET.Element, tag: str, pdo: Pdo, sm: int | None, fixed: bool,
         per_slot: bool = False) -> None:
    """One RxPdo / TxPdo. ``sm``: the sync manager it is assigned to by default; None for a
    PDO the master may assign (ETG.2000: a PDO without Sm is not in the default assignment).
    ``per_slot``: a module PDO of a modular device, whose index and entries' indices move by
    the slot's increments; ETG.2000 moves only an Index marked DependOnSlot, so a
    configurator reading the module without the mark puts every slot's PDO at module 1's.
    """
    attrs = {"Fixed": "1" if fixed else "0"}
    if pdo.mandatory:
        attrs["Mandatory"] = "1"
    if sm is not None:
        attrs["Sm"] = str(sm)
    moves = {"DependOnSlot": "1"} if per_slot else {}
    el = ET.SubElement(parent, tag, attrs)
    _text(el, "Index", hexid(pdo.index, 4), **moves)
    _text(el, "Name", pdo.name)
    for e in pdo.entries:
        entry = ET.SubElement(el, "Entry")
        _text(entry, "Index", hexid(e.index, 4), **(moves if e.index else {}))
        if e.index:
            _text(entry, "SubIndex", str(e.sub))
        _text(entry, "BitLen", str(e.bits))
        if e.index:
            _text(entry, "Name", e.name)
            _text(entry, "DataType", e.data_type or DATA_TYPES.get(e.bits, f"BIT{e.bits}"))


def _sm_number(desc: SlaveDescription, kind: int, default: int) -> int:
    return next((n for n, sm in enumerate(desc.sync_managers) if sii.sm_type(sm) == kind),
                default)


def device_element(desc: SlaveDescription) -> ET.Element:
    dev = ET.Element("Device", {"Physics": "YY"})
    _text(dev, "Type", desc.order_code or desc.name, ProductCode=hexid(desc.product_code),
          RevisionNo=hexid(desc.revision))
    _text(dev, "Name", desc.name, LcId="1033")
    _text(dev, "GroupType", desc.group)
    if desc.diag_texts:
        _profile(dev, desc)
    fmmus = [sii.FMMU_OUTPUTS, sii.FMMU_INPUTS] + ([sii.FMMU_MBX_STATE] if desc.mailbox else [])
    for f in fmmus[:desc.fmmu_count]:
        _text(dev, "Fmmu", FMMU_NAMES[f])
    for sm in desc.sync_managers:
        kind = sii.sm_type(sm)
        attrs = {"StartAddress": hexid(sm.start, 4), "ControlByte": hexid(sm.control, 2),
                 "Enable": str(sm.enable & 1)}
        if sm.length:
            attrs["DefaultSize"] = str(sm.length)
        _text(dev, "Sm", SM_NAMES.get(kind, ""), **attrs)
    rx_sm = _sm_number(desc, sii.SM_TYPE_OUTPUTS, 2)
    tx_sm = _sm_number(desc, sii.SM_TYPE_INPUTS, 3)
    # The assigned PDOs first, in assignment order (a configurator builds the image in the
    # order it reads them), then the ones the master may add.
    own = desc.device_pdos
    for tag, assigned, spare, sm in (("RxPdo", desc.rx_pdos, desc.spare_rx_pdos, rx_sm),
                                     ("TxPdo", desc.tx_pdos, desc.spare_tx_pdos, tx_sm)):
        # a modular device's module PDOs come with the modules in its slots
        for pdo in assigned:
            if own is None or pdo.index in own:
                _pdo(dev, tag, pdo, sm, desc.pdos_fixed)
        for pdo in spare:
            if own is None or pdo.index in own:
                _pdo(dev, tag, pdo, None, desc.pdos_fixed)
    if desc.mailbox is not None:
        mbx = ET.SubElement(dev, "Mailbox", {"DataLinkLayer": "true"})
        ET.SubElement(mbx, "CoE", {name: "true" if desc.coe_details & bit else "false"
                                   for name, bit in COE_FLAGS})
    if desc.dc_supported:
        dc = ET.SubElement(dev, "Dc")
        modes = [("FreeRun", desc.sm_mode_desc, 0), ("DC", "DC-Synchron", 0x0300)]
        if desc.dc_default:  # the first OpMode is the one a configurator selects
            modes.reverse()
        for name, desc_text, assign in modes:
            mode = ET.SubElement(dc, "OpMode")
            _text(mode, "Name", name)
            _text(mode, "Desc", desc_text)
            _text(mode, "AssignActivate", hexid(assign, 4))
            if assign:
                _text(mode, "CycleTimeSync0", "0", Factor="1")
                _text(mode, "ShiftTimeSync0", "0")
    if desc.slot_modules:
        _slots(dev, desc)
    image = sii.build(desc)
    eeprom = ET.SubElement(dev, "Eeprom")
    _text(eeprom, "ByteSize", str(len(image)))
    _text(eeprom, "ConfigData", image[:14].hex().upper())
    return dev


def _profile(dev: ET.Element, desc: SlaveDescription) -> None:
    """ETG.2000 Profile (between GroupType and Fmmu): ProfileNo, then DiagMessages, the text
    a configurator shows for a 0x10F3 message by its Text-ID, one MessageText per LcId."""
    profile = ET.SubElement(dev, "Profile")
    _text(profile, "ProfileNo", str(desc.profile_no))
    messages = ET.SubElement(profile, "DiagMessages")
    for diag in desc.diag_texts:
        message = ET.SubElement(messages, "DiagMessage")
        _text(message, "TextId", hexid(diag.text_id, 4))
        for lcid, text in diag.texts:
            _text(message, "MessageText", text, LcId=str(lcid))


def _slots(dev: ET.Element, desc: SlaveDescription) -> None:
    """The Slot elements: with slot_count 1 one slot taking exactly one of the modules (they
    are alternatives: the drive); more, up to slot_count slots in a row, none required, each
    module's PDOs and objects moved by the increments per slot (a modular device, the
    FastCAT); or the slot_groups in order, where the slots take different modules (the
    TRS-CAT). DownloadModuleIdentList: whether the slave has a 0xF030 to write."""
    attrs = {"DownloadModuleIdentList": "1" if desc.download_module_idents else "0"}
    if _modular(desc):
        attrs.update(SlotPdoIncrement=str(desc.slot_pdo_increment),
                     SlotIndexIncrement=hexid(desc.slot_index_increment, 2))
    slots = ET.SubElement(dev, "Slots", attrs)
    groups = desc.slot_groups or (SlotGroup(
        desc.slot_name, 1 if desc.slot_count == 1 else 0, desc.slot_count,
        tuple(m.ident for m in desc.slot_modules),
        next((m.ident for m in desc.slot_modules if m.default), 0)),)
    for group in groups:
        slot = ET.SubElement(slots, "Slot", {"MinInstances": str(group.min_instances),
                                             "MaxInstances": str(group.max_instances)})
        _text(slot, "Name", group.name, LcId="1033")
        for ident in group.idents:
            _text(slot, "ModuleIdent", hexid(ident),
                  **({"Default": "1"} if ident == group.default else {}))


def _modular(desc: SlaveDescription) -> bool:
    """A modular device: its modules' PDOs and objects move from slot to slot."""
    return bool(desc.slot_pdo_increment or desc.slot_index_increment)


def modules_element(desc: SlaveDescription) -> ET.Element:
    """Descriptions/Modules: each module's PDOs, assigned to SM2 / SM3 while it is plugged."""
    rx_sm = _sm_number(desc, sii.SM_TYPE_OUTPUTS, 2)
    tx_sm = _sm_number(desc, sii.SM_TYPE_INPUTS, 3)
    per_slot = _modular(desc)
    modules = ET.Element("Modules")
    for module in desc.slot_modules:
        el = ET.SubElement(modules, "Module")
        _text(el, "Type", module.type_name, ModuleIdent=hexid(module.ident))
        _text(el, "Name", module.name, LcId="1033")
        for pdo in module.rx_pdos:
            _pdo(el, "RxPdo", pdo, rx_sm, desc.pdos_fixed, per_slot)
        for pdo in module.tx_pdos:
            _pdo(el, "TxPdo", pdo, tx_sm, desc.pdos_fixed, per_slot)
    return modules


def document(desc: SlaveDescription, vendor_name: str | None = None) -> ET.ElementTree:
    root = ET.Element("EtherCATInfo", {
        "xmlns:xsi": "http://www.w3.org/2001/XMLSchema-instance",
        "xsi:noNamespaceSchemaLocation": "EtherCATInfo.xsd", "Version": "1.6"})
    vendor = ET.SubElement(root, "Vendor")
    _text(vendor, "Id", hexid(desc.vendor_id))
    _text(vendor, "Name",
          vendor_name or desc.vendor_name or f"{desc.name} (FieldRig virtual slave)")
    descriptions = ET.SubElement(root, "Descriptions")
    group = ET.SubElement(ET.SubElement(descriptions, "Groups"), "Group")
    _text(group, "Type", desc.group)
    _text(group, "Name", desc.group, LcId="1033")
    ET.SubElement(descriptions, "Devices").append(device_element(desc))
    if desc.slot_modules:
        descriptions.append(modules_element(desc))
    tree = ET.ElementTree(root)
    ET.indent(tree)
    return tree


def file_name(desc: SlaveDescription) -> str:
    return "FieldRig_" + re.sub(r"[^A-Za-z0-9_-]+", "_", desc.name).strip("_") + ".xml"


def write(descriptions: list[SlaveDescription], out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for desc in descriptions:
        path = out / file_name(desc)
        document(desc).write(path, encoding="ISO-8859-1", xml_declaration=True)
        paths.append(path)
    return paths


def rig_descriptions(rig: Any) -> list[SlaveDescription]:
    """The line of a rig as the wire shows it: power on, let the slaves boot, describe."""
    from app.ethercat_wire.faces import face_for

    for device in rig.devices.values():
        if "power" in device.ACTIONS:
            device.apply("power", {"on": True}, None)
    master = rig.devices.get("master")
    if master is None:
        raise ValueError("the rig has no EtherCAT line ([master] line)")
    line = [(link.slave, face_for(link.slave)) for link in master.links]
    while not all(face.ready(m) for m, face in line) and rig.clock.now_us < BOOT_LIMIT_US:
        rig.run_until(rig.clock.now_us + 100_000)
    return [face.describe(m) for m, face in line]


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="python -m app ethercat",
                    description="EtherCAT wire tools: ESI files of the rig's line for a "
                                "configurator (docs/ethercat-wire.md).")
    sub = parser.add_subparsers(dest="verb", required=True)
    export = sub.add_parser("export-esi", help="write ESI XML files for the rig's line")
    export.add_argument("--rig", default=None, help="rig file (default: the default rig)")
    export.add_argument("--out", default=str(DEFAULT_OUT),
                        help=f"output folder (default: {DEFAULT_OUT} in the working directory: "
                             "in the checkout, the shipped files)")
    args = parser.parse_args(argv)
    from app.out_paths import check_out
    from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec

    out = check_out(args.out, names=())  # before any work, as scenario run's --out
    rig_file = args.rig or DEFAULT_RIG
    rig = build_rig(load_rig_spec(rig_file))
    if "master" not in rig.devices:
        raise RigConfigError(str(rig_file), "", "the rig has no EtherCAT line (no [[fastcat]], "
                             "[[trscat]], [[cpx]] or drive with fieldbus = \"ethercat\"): no "
                             "ESI to export")
    for path in write(rig_descriptions(rig), out):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
