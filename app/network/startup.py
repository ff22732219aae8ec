"""The start-up values a rig file gives a slave, as the built-in master's CoE init commands.

A rig file may say what the master's start-up writes into a slave (TwinCAT's "Startup" tab):
today the CPX-E-EC's ``history_flags``, 0x10F3:5 written in PS (seed 002 Tab. 14: the object
powers up 0x0000; docs/cpx-e-ec.md choice 19). The model never reads the value; the master
sends it, so a master on the wire (docs/ethercat-wire.md) that writes nothing leaves 0x0000.
With a network description the command joins the slave's init commands (a description made
before the command existed keeps working); one that writes another value is an error. Without
one, the slave gets a description derived from the rig that carries only these commands.
"""

from __future__ import annotations

import dataclasses
import struct
from collections.abc import Mapping, Sequence

from devices.master.master import FIRST_STATION_ADDRESS
from devices.master.network import InitCmd, SlaveDescription

HISTORY_FLAGS = (0x10F3, 5)
HISTORY_FLAGS_COMMENT = "CPX-E-EC: diagnosis history flags"


def history_flags_command(value: int) -> InitCmd:
    """0x10F3:5 in PS: the transition a TwinCAT user sees a CoE object's start-up entry at."""
    return InitCmd("PS", *HISTORY_FLAGS, struct.pack("<H", value), HISTORY_FLAGS_COMMENT)


def rig_commands(slaves: Sequence[tuple[str, str, Mapping[str, object]]]
                 ) -> dict[str, tuple[str, InitCmd]]:
    """Device id -> (the rig key that gave it, its init command), from (kind, id, settings)."""
    out: dict[str, tuple[str, InitCmd]] = {}
    count: dict[str, int] = {}
    for kind, device_id, settings in slaves:
        i = count[kind] = count.get(kind, -1) + 1
        flags = settings.get("history_flags")
        if kind == "cpx" and isinstance(flags, int):
            out[device_id] = (f"cpx[{i}].history_flags", history_flags_command(flags))
    return out


class StartupConflict(ValueError):
    def __init__(self, key: str, reason: str) -> None:
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


def with_rig_commands(descriptions: Sequence[SlaveDescription] | None, line: Sequence[str],
                      commands: Mapping[str, tuple[str, InitCmd]], dc: Sequence[bool],
                      eni: str | None) -> list[SlaveDescription | None] | None:
    """The master's descriptions with the rig's start-up commands added (None: no
    description and no command). StartupConflict when the description writes another value."""
    if descriptions is None and not commands:
        return None
    out: list[SlaveDescription | None] = []
    for position, device_id in enumerate(line):
        desc = descriptions[position] if descriptions is not None else None
        if device_id in commands:
            key, cmd = commands[device_id]
            desc = _joined(desc, cmd, key, eni) if desc is not None else SlaveDescription(
                position, "", device_id, None, None, None, FIRST_STATION_ADDRESS + position,
                dc[position], (cmd,))
        out.append(desc)
    return out


def _joined(desc: SlaveDescription, cmd: InitCmd, key: str, eni: str | None) -> SlaveDescription:
    same = [c for c in desc.init_cmds if (c.index, c.sub) == (cmd.index, cmd.sub)]
    if not same:
        return dataclasses.replace(desc, init_cmds=(*desc.init_cmds, cmd))
    other = [c for c in same if c.data != cmd.data]
    if other:
        raise StartupConflict(key, f"0x{_value(cmd):04X}, but {eni} writes "
                                   f"0x{cmd.index:04X}:{cmd.sub} = 0x{_value(other[0]):04X} "
                                   f"({other[0].transition}): give one value (regenerate the "
                                   f"description: python -m app.network.generate)")
    return desc


def _value(cmd: InitCmd) -> int:
    return int.from_bytes(cmd.data, "little")
