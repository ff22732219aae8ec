"""The Modbus fuzz oracle: what the drive line owes each request, worked out without serve_line.

From the rules of docs/modbus.md (seed 004 ch.2 "Codici funzione", "Codice 03 / 06 / 16",
"Eccezioni", "Estensione della mappatura") and the drive's own parameter and register tables,
:func:`due` says, for one request and the line's state before it, which answer is owed:

- ``silence`` for the documented reasons only: a function code other than 03 / 06 / 16, a
  broadcast (unit 0) or a reserved / unheld / shared unit id, a drive that does not listen, a
  wrong length, quantity or byte count, an odd register quantity above 1, a value out of range
  or a read-only target;
- ``e02`` when the start address, or any address of the block, names nothing;
- ``read``: a correct reply, its data read from the drive's registers directly;
- ``write``: the echo, and the value must be in the drive afterwards.

:func:`judge` holds an outcome against that; anything but a reply leaves the line unchanged
(a broadcast write may change it: it is applied, never answered).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from app.modbus.pdu import Exception02, Outcome, Reply, Silence
from devices.servo.control import BIT5, POSITIONER
from devices.servo.errors import AccessError
from devices.servo.parameters import (
    MODBUS_NODE_HIGH,
    PARAMETER_BY_NAME,
    PARAMETERS,
    SAVE_COMMAND_ADDRESS,
    SAVE_COMMAND_VALUE,
    check_node_number,
)
from devices.servo.registers import REGISTER_BASE, REGISTERS, R

FC03, FC06, FC16 = 0x03, 0x06, 0x10
E3_ADDRESS, E3_SIEMENS = 58, 9
SIEMENS_PARAMETER_BASE, SIEMENS_REGISTER_BASE = 40001, 44097
MAX_READ = 125
C7, C9 = PARAMETER_BY_NAME["c7"].address, PARAMETER_BY_NAME["c9"].address

State = tuple[Any, ...]


def drive_state(drive: Any) -> State:
    """Everything a request could change: the snapshot plus the raw parameter and register
    tables. Nothing steps between two captures, so no field varies with time in between."""
    return drive.snapshot(), dict(drive.params), dict(drive.regs)


def line_state(drives: Sequence[Any]) -> list[State]:
    return [drive_state(d) for d in drives]


@dataclass(frozen=True)
class Due:
    kind: str  # "silence", "e02", "read", "write"
    why: str
    target: tuple[str, int] = ("", 0)  # ("parameter" | "register" | "save", index)
    quantity: int = 0  # words read
    values: tuple[int, ...] = field(default=())  # what a write stores, one per target


def _u16(value: int) -> bytes:
    return (value & 0xFFFF).to_bytes(2, "big")


def _locate(address: int, siemens: bool) -> tuple[str, int]:
    if address == SAVE_COMMAND_ADDRESS:
        return "save", address
    if siemens:
        if address >= SIEMENS_REGISTER_BASE:
            return "register", address - SIEMENS_REGISTER_BASE
        if address >= SIEMENS_PARAMETER_BASE:
            return "parameter", address - SIEMENS_PARAMETER_BASE
        return "nothing", address
    if address >= REGISTER_BASE:
        return "register", address - REGISTER_BASE
    return "parameter", address


def _exists(kind: str, index: int) -> bool:
    return index in (REGISTERS if kind == "register" else PARAMETERS)


def _sign16(word: int) -> int:
    return (word - 0x10000 if word & 0x8000 else word) & 0xFFFF_FFFF


def _refusal(kind: str, index: int, value: int, params: dict[int, int]) -> str | None:
    """Why the drive must refuse this value at this target (None: it must take it)."""
    spec: Any = REGISTERS[index] if kind == "register" else PARAMETERS[index]
    if not spec.writable:
        return f"{spec.name} is read-only"
    try:
        spec.check(value)
        if kind == "parameter" and index == C7:
            check_node_number(value, params[C9])
    except AccessError as exc:
        return str(exc)
    return None


def _stored(kind: str, index: int, value: int) -> int:
    return REGISTERS[index].check(value) if kind == "register" else value


def _due_read(pdu: bytes, siemens: bool) -> Due:
    address, quantity = int.from_bytes(pdu[1:3], "big"), int.from_bytes(pdu[3:5], "big")
    if not 1 <= quantity <= MAX_READ:
        return Due("silence", f"quantity {quantity}")
    kind, index = _locate(address, siemens)
    if kind in ("save", "nothing") or not _exists(kind, index):
        return Due("e02", f"nothing readable at 0x{address:04X}")
    if kind == "register":
        if quantity == 1:
            return Due("read", "low word", (kind, index), 1)
        if quantity % 2:
            return Due("silence", f"odd quantity {quantity} on registers")
        numbers = range(index, index + quantity // 2)
    else:
        numbers = range(index, index + quantity)
    if not all(_exists(kind, n) for n in numbers):
        return Due("e02", "the block leaves the map")
    return Due("read", "block", (kind, index), quantity)


def _due_write(pdu: bytes, siemens: bool, params: dict[int, int]) -> Due:
    address = int.from_bytes(pdu[1:3], "big")
    if pdu[0] == FC06:
        words = [int.from_bytes(pdu[3:5], "big")]
    else:
        quantity = int.from_bytes(pdu[3:5], "big")
        if quantity not in (1, 2):
            return Due("silence", f"FC 16 quantity {quantity}")
        if pdu[5] != 2 * quantity or len(pdu) != 6 + pdu[5]:
            return Due("silence", "FC 16 byte count or length")
        words = [int.from_bytes(pdu[6 + 2 * i:8 + 2 * i], "big") for i in range(quantity)]
    kind, index = _locate(address, siemens)
    whole = words[0] << 16 | words[1] if len(words) == 2 else words[0]
    if kind == "save":
        ok = whole == SAVE_COMMAND_VALUE
        return Due("write", "save", (kind, index)) if ok else Due("silence", "save value")
    if kind == "nothing" or not _exists(kind, index):
        return Due("e02", f"nothing writable at 0x{address:04X}")
    if kind == "register":
        values = [whole if len(words) == 2 else _sign16(words[0])]
    else:
        values = words
        if not all(_exists(kind, index + i) for i in range(len(words))):
            return Due("e02", "the second parameter does not exist")
    for i, value in enumerate(values):
        refusal = _refusal(kind, index + i, value, params)
        if refusal:
            return Due("silence", refusal)
    stored = tuple(_stored(kind, index + i, v) for i, v in enumerate(values))
    return Due("write", "store", (kind, index), values=stored)


def due(before: list[State], unit: int, pdu: bytes) -> Due:
    """What the line owes ``pdu`` sent to ``unit`` when the drives were in ``before``."""
    if not pdu or pdu[0] not in (FC03, FC06, FC16):
        return Due("silence", "function code")
    if unit == 0:
        return Due("silence", "broadcast")
    if unit > MODBUS_NODE_HIGH:
        return Due("silence", "reserved unit id")
    listening = [i for i, (snap, _p, _r) in enumerate(before)
                 if snap["node_id"] == unit and snap["responding"] and snap["fieldbus"] == "modbus"]
    if len(listening) != 1:
        return Due("silence", f"{len(listening)} drives listen at unit {unit}")
    if (pdu[0] in (FC03, FC06) and len(pdu) != 5) or (pdu[0] == FC16 and len(pdu) < 6):
        return Due("silence", "length")
    params = before[listening[0]][1]
    siemens = params[E3_ADDRESS] == E3_SIEMENS
    return _due_read(pdu, siemens) if pdu[0] == FC03 else _due_write(pdu, siemens, params)


def _listener(drives: Sequence[Any], before: list[State], unit: int) -> Any:
    return next(d for d, (snap, _p, _r) in zip(drives, before, strict=True)
                if snap["node_id"] == unit and snap["responding"])


def _read_data(drive: Any, target: tuple[str, int], quantity: int) -> bytes:
    kind, index = target
    if kind == "register":
        if quantity == 1:
            return _u16(drive.read_register(index))
        return b"".join((drive.read_register(n) & 0xFFFF_FFFF).to_bytes(4, "big")
                        for n in range(index, index + quantity // 2))
    return b"".join(_u16(drive.read_parameter(a)) for a in range(index, index + quantity))


def _landed(drive: Any, expectation: Due, mode_before: int) -> str | None:
    kind, index = expectation.target
    table = drive.regs if kind == "register" else drive.params
    for i, value in enumerate(expectation.values):
        held = table[index + i]
        if kind == "register" and index + i == R.CONTROL_WORD and mode_before in POSITIONER:
            # Pos_str (bit 5) "returns to 0 by itself" once the set-point is taken (ch.2),
            # which can be within the write itself
            held, value = held & ~BIT5, value & ~BIT5
        if held != value:
            return f"{kind} {index + i} holds {table[index + i]}, the write said {value}"
    if kind == "save" and not (drive.saving or drive.save_pending):
        return "the save command was answered but no save started"
    return None


def judge(drives: Sequence[Any], unit: int, pdu: bytes, outcome: Outcome,
          before: list[State]) -> str | None:
    """Why ``outcome`` is wrong for this request (None: it is right)."""
    after = line_state(drives)
    expectation = due(before, unit, pdu)
    kind = expectation.kind
    if kind == "silence":
        if not isinstance(outcome, Silence):
            return f"answered {outcome!r}, silence due ({expectation.why})"
        applied = unit == 0 and pdu[:1] in (bytes((FC06,)), bytes((FC16,)))
        return None if applied or after == before else "state changed by a silenced request"
    if kind == "e02":
        if outcome != Exception02(pdu[0]):
            return f"got {outcome!r}, exception 02 due ({expectation.why})"
        return None if after == before else "state changed by a request answered with 02"
    if not isinstance(outcome, Reply):
        return f"got {outcome!r}, a reply due ({expectation.why})"
    drive = _listener(drives, before, unit)
    if kind == "read":
        data = _read_data(drive, expectation.target, expectation.quantity)
        want = bytes((FC03, len(data))) + data
        if outcome.pdu != want:
            return f"FC 03 reply {outcome.pdu.hex(' ')}, expected {want.hex(' ')}"
        return None if after == before else "state changed by a read"
    want = pdu if pdu[0] == FC06 else pdu[:5]
    if outcome.pdu != want:
        return f"write reply {outcome.pdu.hex(' ')}, expected {want.hex(' ')}"
    mode_before = next(regs for (snap, _p, regs) in before if snap["node_id"] == unit
                       and snap["responding"])[R.MODES_OF_OPERATION]
    return _landed(drive, expectation, mode_before)
