"""The start-up values a rig file gives a slave, as the built-in master's CoE init commands.

A rig file may say what the master's start-up writes into a slave (TwinCAT's "Startup" tab):
the CPX-E-EC's ``history_flags``, 0x10F3:5 written in PS (seed 002 Tab. 14: the object powers
up 0x0000; docs/cpx-e-ec.md choice 19), and the TRS-CAT's ``configured`` list, 0xF030 written
in PS (seed 001 §9.2 PS, §9.3.2: the object powers up 1 / 0x494F2D42; docs/trscat.md "Who
writes 0xF030"). The models never read these values; the master sends them, so a master on
the wire (docs/ethercat-wire.md) that writes nothing leaves the objects' power-up values.
With a network description the commands join the slave's init commands (a description made
before they existed keeps working); one that writes other values to the same object is an
error. Without one, the slave gets a description derived from the rig that carries only
these commands.
"""

from __future__ import annotations

import dataclasses
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from devices.master.master import FIRST_STATION_ADDRESS
from devices.master.network import InitCmd, SlaveDescription
from devices.trscat.catalog import BY_IDENT, INTEGRATED, ModuleKind, expansion_list

HISTORY_FLAGS = (0x10F3, 5)
HISTORY_FLAGS_COMMENT = "CPX-E-EC: diagnosis history flags"
MODULE_LIST = 0xF030  # ETG.5001 Configured Module Ident List (seed 001 §9.3.2, seed 002)


def history_flags_command(value: int) -> InitCmd:
    """0x10F3:5 in PS: the transition a TwinCAT user sees a CoE object's start-up entry at."""
    return InitCmd("PS", *HISTORY_FLAGS, struct.pack("<H", value), HISTORY_FLAGS_COMMENT)


def f030_commands(idents: Sequence[int], count: bytes, what: str) -> tuple[InitCmd, ...]:
    """A configured module list as a configurator writes it in PS: sub 0, then subs 1..n."""
    cmds = [InitCmd("PS", MODULE_LIST, 0, count, f"{what}: configured module list, count")]
    cmds += [InitCmd("PS", MODULE_LIST, sub, struct.pack("<I", ident),
                     f"{what}: configured module {sub}")
             for sub, ident in enumerate(idents, start=1)]
    return tuple(cmds)


def trscat_list_commands(idents: Sequence[int]) -> tuple[InitCmd, ...]:
    """The TRS-CAT's 0xF030 (sub 0 U8, §9.3.2), the integrated module first."""
    return f030_commands(idents, struct.pack("<B", len(idents)), "TRS-CAT")


@dataclass(frozen=True)
class StartupValue:
    """What one rig key makes the master write: ``cmds`` to one object (all of it when sub 0
    is among them), ``shown`` the rig's value as the error names it."""
    key: str
    cmds: tuple[InitCmd, ...]
    shown: str


def rig_commands(slaves: Sequence[tuple[str, str, Mapping[str, object]]]
                 ) -> dict[str, StartupValue]:
    """Device id -> its start-up value, from (kind, id, settings) of checked rig slaves."""
    out: dict[str, StartupValue] = {}
    count: dict[str, int] = {}
    for kind, device_id, settings in slaves:
        i = count[kind] = count.get(kind, -1) + 1
        flags = settings.get("history_flags")
        if kind == "cpx" and isinstance(flags, int):
            out[device_id] = StartupValue(f"cpx[{i}].history_flags",
                                          (history_flags_command(flags),), f"0x{flags:04X}")
        configured = settings.get("configured")
        if kind == "trscat" and isinstance(configured, list):
            kinds = [INTEGRATED, *expansion_list(configured, "configured expansion")]
            out[device_id] = StartupValue(f"trscat[{i}].configured",
                                          trscat_list_commands([k.ident for k in kinds]),
                                          _module_names(kinds[1:]))
    return out


def _module_names(kinds: Sequence[ModuleKind]) -> str:
    return ", ".join(k.name for k in kinds) or "no expansion"


class StartupConflict(ValueError):
    def __init__(self, key: str, reason: str) -> None:
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


def with_rig_commands(descriptions: Sequence[SlaveDescription] | None, line: Sequence[str],
                      commands: Mapping[str, StartupValue], dc: Sequence[bool],
                      eni: str | None) -> list[SlaveDescription | None] | None:
    """The master's descriptions with the rig's start-up commands added (None: no
    description and no command). StartupConflict when the description writes another value."""
    if descriptions is None and not commands:
        return None
    out: list[SlaveDescription | None] = []
    for position, device_id in enumerate(line):
        desc = descriptions[position] if descriptions is not None else None
        if device_id in commands:
            value = commands[device_id]
            desc = _joined(desc, value, eni) if desc is not None else SlaveDescription(
                position, "", device_id, None, None, None, FIRST_STATION_ADDRESS + position,
                dc[position], value.cmds)
        out.append(desc)
    return out


def _joined(desc: SlaveDescription, value: StartupValue, eni: str | None) -> SlaveDescription:
    """The description with the rig's commands; unchanged when it writes the same values to
    the object, StartupConflict when it writes others."""
    whole = {c.index for c in value.cmds if c.sub == 0}
    subs = {(c.index, c.sub) for c in value.cmds}
    same = [c for c in desc.init_cmds if c.index in whole or (c.index, c.sub) in subs]
    if not same:
        return dataclasses.replace(desc, init_cmds=(*desc.init_cmds, *value.cmds))
    if _written(same) != _written(value.cmds):
        raise StartupConflict(value.key, f"{value.shown}, but {eni} writes "
                                         f"{_shown(same)}: give one "
                                         f"{'list' if whole else 'value'} (regenerate the "
                                         f"description: python -m app.network.generate)")
    return desc


def _written(cmds: Sequence[InitCmd]) -> dict[tuple[int, int], int]:
    return {(c.index, c.sub): _value(c) for c in cmds}


def _shown(cmds: Sequence[InitCmd]) -> str:
    """The description's commands as a trainee compares them with the rig: a module list by
    its modules' names, a single value in hex."""
    if cmds[0].index == MODULE_LIST:
        values = _written(cmds)
        count = values.get((MODULE_LIST, 0), 0)
        idents = [values.get((MODULE_LIST, sub), 0) for sub in range(2, count + 1)]
        names = [BY_IDENT[i].name if i in BY_IDENT else f"0x{i:08X}" for i in idents]
        return f"0xF030 = {', '.join(names) or 'no expansion'} ({cmds[0].transition})"
    return (f"0x{cmds[0].index:04X}:{cmds[0].sub} = 0x{_value(cmds[0]):04X} "
            f"({cmds[0].transition})")


def _value(cmd: InitCmd) -> int:
    return int.from_bytes(cmd.data, "little")
