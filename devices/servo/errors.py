"""Errors of the servo drive's register/parameter interface.

An :class:`AccessError` always leaves the drive unchanged: every check runs before a value is
stored. It is a :class:`~devices.device.CommandError`, so operator and scenario actions report it
like any refused command, and protocol adapters map ``kind`` onto their wire (the Modbus side
answers exception 02 only for ``"address"`` and stays silent otherwise, seed 004 ch. 2
"Eccezioni").
"""

from __future__ import annotations

from typing import Literal

from devices.device import CommandError

AccessKind = Literal["address", "readonly", "value"]


class AccessError(CommandError):
    """A register or parameter access the drive refuses."""

    def __init__(self, kind: AccessKind, message: str) -> None:
        self.kind: AccessKind = kind
        super().__init__(message)
