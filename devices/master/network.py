"""The network description (ENI-like) and the mapping file, parsed from text (seed 003 ¶1-2).

Seed 003: the master reads an ENI (EtherCAT Network Information: the slaves in line order with
their identity and init commands) and an XML configuration (PLC variables -> PDO entries,
plus master parameters). FieldRig's two formats are a small ENI subset (docs/
ethercat-master.md has an example of each); numbers are decimal or ENI hex (``#x1C32``).
Nothing in a file executes: a DOCTYPE or ENTITY is refused before ElementTree sees the text.
Errors are :class:`NetworkFileError` with the element's path.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from devices.names import did_you_mean

TRANSITIONS = ("IP", "PS", "SO", "SP", "OS", "OP", "PI", "SI", "OI")  # ETG.1000.6 names
DIRECTIONS = ("input", "output")
_FORBIDDEN = re.compile(r"<!\s*(DOCTYPE|ENTITY)", re.IGNORECASE)


class NetworkFileError(ValueError):
    def __init__(self, element: str, reason: str) -> None:
        self.element, self.reason = element, reason
        super().__init__(f"{element}: {reason}" if element else reason)


@dataclass(frozen=True)
class InitCmd:
    """A CoE SDO download the master sends on a transition (``PS`` = PREOP -> SAFEOP)."""

    transition: str
    index: int
    sub: int
    data: bytes
    comment: str = ""


@dataclass(frozen=True)
class SlaveDescription:
    position: int
    name: str  # the box name the master logs
    device: str  # the rig's device id of the slave at this position
    vendor: int | None  # None (a description derived from the rig): identity not checked
    product: int | None
    revision: int | None
    station_address: int
    dc: bool
    init_cmds: tuple[InitCmd, ...] = ()

    def commands(self, transition: str) -> tuple[InitCmd, ...]:
        return tuple(c for c in self.init_cmds if c.transition == transition)


@dataclass(frozen=True)
class Variable:
    """A PLC variable mapped to a PDO entry of the slave at ``position``."""

    name: str
    position: int
    index: int
    sub: int
    bit_length: int
    direction: str  # "input" (slave -> PLC) or "output"


@dataclass(frozen=True)
class MasterParameters:
    cycle_us: int = 1000
    dc_window_ns: int = 1000


@dataclass(frozen=True)
class Mapping:
    parameters: MasterParameters
    variables: tuple[Variable, ...] = ()


def _root(text: str, what: str) -> ET.Element:
    if _FORBIDDEN.search(text):
        raise NetworkFileError("", f"{what}: DOCTYPE / ENTITY declarations are not accepted")
    try:
        return ET.fromstring(text)
    except ET.ParseError as exc:
        raise NetworkFileError("", f"{what}: not well-formed XML: {exc}") from None


def number(text: str | None, where: str) -> int:
    """ENI numbers: decimal, ``#x`` hex (ENI) or ``0x`` hex."""
    raw = (text or "").strip()
    try:
        if raw.lower().startswith(("#x", "0x")):
            return int(raw[2:], 16)
        return int(raw, 10)
    except ValueError:
        raise NetworkFileError(where, f"not a number: {raw!r}") from None


def _child(el: ET.Element, tag: str, where: str) -> ET.Element:
    found = el.find(tag)
    if found is None:
        raise NetworkFileError(where, f"missing <{tag}>")
    return found


def _text(el: ET.Element, tag: str, where: str) -> str:
    return (_child(el, tag, where).text or "").strip()


def _bool(text: str | None, where: str) -> bool:
    raw = (text or "").strip().lower()
    if raw in ("true", "1"):
        return True
    if raw in ("false", "0"):
        return False
    raise NetworkFileError(where, f"not true/false: {raw!r}")


def parse_eni(text: str) -> tuple[SlaveDescription, ...]:
    root = _root(text, "network description")
    if root.tag != "EtherCATConfig":
        raise NetworkFileError(root.tag, "the root element must be <EtherCATConfig>")
    config = _child(root, "Config", "EtherCATConfig")
    slaves = []
    for position, el in enumerate(config.findall("Slave")):
        where = f"Config/Slave[{position}]"
        info = _child(el, "Info", where)
        iw = f"{where}/Info"
        dc_el = el.find("DC")
        cmds = []
        for j, cmd in enumerate(el.findall("Mailbox/CoE/InitCmds/InitCmd")):
            cw = f"{where}/Mailbox/CoE/InitCmds/InitCmd[{j}]"
            transition = _text(cmd, "Transition", cw)
            if transition not in TRANSITIONS:
                raise NetworkFileError(f"{cw}/Transition", f"unknown transition "
                                       f"{transition!r} (known: {', '.join(TRANSITIONS)})"
                                       f"{did_you_mean(transition, TRANSITIONS)}")
            data_hex = _text(cmd, "Data", cw)
            try:
                data = bytes.fromhex(data_hex)
            except ValueError:
                raise NetworkFileError(f"{cw}/Data", f"not hex bytes: {data_hex!r}") from None
            cmds.append(InitCmd(transition, number(_text(cmd, "Index", cw), f"{cw}/Index"),
                                number(_text(cmd, "SubIndex", cw), f"{cw}/SubIndex"), data,
                                (cmd.findtext("Comment") or "").strip()))
        address = number(_text(info, "PhysAddr", iw), f"{iw}/PhysAddr")
        if not 1 <= address <= 0xFFFF:
            raise NetworkFileError(f"{iw}/PhysAddr", f"{address} is not a station address "
                                                     f"(1..65535)")
        slaves.append(SlaveDescription(
            position=position, name=_text(info, "Name", iw), device=_text(info, "Device", iw),
            vendor=number(_text(info, "VendorId", iw), f"{iw}/VendorId"),
            product=number(_text(info, "ProductCode", iw), f"{iw}/ProductCode"),
            revision=number(_text(info, "RevisionNo", iw), f"{iw}/RevisionNo"),
            station_address=address,
            dc=dc_el is not None and _bool(dc_el.findtext("Use", "true"), f"{where}/DC/Use"),
            init_cmds=tuple(cmds)))
    seen: dict[int, int] = {}
    for s in slaves:
        if s.station_address in seen:
            raise NetworkFileError(f"Config/Slave[{s.position}]/Info/PhysAddr",
                                   f"{s.station_address} is already slave "
                                   f"{seen[s.station_address]}'s")
        seen[s.station_address] = s.position
    return tuple(slaves)


def parse_mapping(text: str) -> Mapping:
    root = _root(text, "mapping")
    if root.tag != "MasterConfig":
        raise NetworkFileError(root.tag, "the root element must be <MasterConfig>")
    params_el = root.find("Parameters")
    params = MasterParameters()
    if params_el is not None:
        cycle = params_el.findtext("CycleTimeUs")
        window = params_el.findtext("DcSyncWindowNs")
        params = MasterParameters(
            cycle_us=number(cycle, "Parameters/CycleTimeUs") if cycle else params.cycle_us,
            dc_window_ns=number(window, "Parameters/DcSyncWindowNs") if window
            else params.dc_window_ns)
        if params.cycle_us <= 0 or params.dc_window_ns <= 0:
            raise NetworkFileError("Parameters", "cycle time and sync window must be > 0")
    variables = []
    for j, el in enumerate(root.findall("Variables/Variable")):
        where = f"Variables/Variable[{j}]"
        name = el.get("Name", "").strip()
        if not name:
            raise NetworkFileError(where, "needs Name=")
        direction = el.get("Direction", "")
        if direction not in DIRECTIONS:
            raise NetworkFileError(f"{where}@Direction", f"{direction!r} is not input or "
                                                         f"output")
        variables.append(Variable(
            name, number(el.get("Slave"), f"{where}@Slave"),
            number(el.get("Index"), f"{where}@Index"),
            number(el.get("SubIndex"), f"{where}@SubIndex"),
            number(el.get("BitLen"), f"{where}@BitLen"), direction))
    return Mapping(params, tuple(variables))


def check_mapping(mapping: Mapping, slaves: tuple[SlaveDescription, ...]) -> None:
    """Every variable names a slave of the description."""
    for j, var in enumerate(mapping.variables):
        if not 0 <= var.position < len(slaves):
            raise NetworkFileError(f"Variables/Variable[{j}]@Slave",
                                   f"no slave at position {var.position} (the description "
                                   f"has {len(slaves)})")
