"""One Modbus request PDU in, drive calls and one outcome out: the servo drive's application
layer exactly as seed 004 chapter 2 describes it ("Codici funzione", "Eccezioni", "Esempi").

Pure: no sockets, no threads, no clock. The server calls :func:`serve_line` in the simulation
thread with the unit id and the PDU (function code + data) that pymodbus de-framed, and sends
what comes back. The rules, with their seed sections, are in docs/modbus.md; in short:

- FC 03, 06 and 16 only; any other function code is discarded without a reply.
- Parameters are 16-bit at their quick-reference address; register Rn is 32-bit at 0x8000 + n.
  FC 03 quantity 1 on Rn reads its low 16 bits, quantity 2k reads Rn..Rn+k-1, each high word
  first; FC 06 on Rn writes the low 16 bits and fills the high 16 with the sign; FC 16 takes
  quantity 1 or 2 only (2 = the whole register, high word first).
- Only exception 02 (illegal data address) is ever answered; every other error (bad length,
  quantity or byte count, a value out of range, a read-only target) gets no reply at all.
- Unit id 0 is a broadcast write (FC 06 / 16) to every drive on the line, never answered;
  unit ids 91..255 are reserved and never answered.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Protocol

from devices.device import CommandError
from devices.servo.errors import AccessError
from devices.servo.modbus_map import (  # e3 = 9: the Siemens map (ch.2), the model's data
    E3_ADDRESS,
    SIEMENS,
    SIEMENS_PARAMETER_BASE,
    SIEMENS_REGISTER_BASE,
    active_map,
)
from devices.servo.parameters import MODBUS_NODE_HIGH  # 91..255 reserved (ch.2)
from devices.servo.parameters import SAVE_COMMAND_ADDRESS as SAVE_ADDRESS
from devices.servo.registers import REGISTER_BASE  # R00 at 0x8000 ... R133 at 0x8085

logger = logging.getLogger(__name__)

FC_READ_HOLDING_REGISTERS = 0x03
FC_WRITE_SINGLE_REGISTER = 0x06
FC_WRITE_MULTIPLE_REGISTERS = 0x10
# ch.2 "Codici funzione": "Le funzioni implementate sul drive sono" 03, 06 and 16; any other
# request is dropped without a reply, so no exception to another function comes from the drive
IMPLEMENTED_FUNCTIONS = (FC_READ_HOLDING_REGISTERS, FC_WRITE_SINGLE_REGISTER,
                         FC_WRITE_MULTIPLE_REGISTERS)
ILLEGAL_DATA_ADDRESS = 0x02  # the only exception code the drive implements (ch.2 "Eccezioni")
EXCEPTION_FLAG = 0x80  # ch.2 "Eccezioni": an exception response sets the function code's MSB
# The Modbus Application Protocol's exception codes, for the Codes tab (app/decoder.py): the
# drive sends 02 only, the others come from other servers (pymodbus itself, a gateway).
EXCEPTION_NAMES: dict[int, str] = {
    0x01: "Illegal Function", ILLEGAL_DATA_ADDRESS: "Illegal Data Address",
    0x03: "Illegal Data Value", 0x04: "Server Device Failure", 0x05: "Acknowledge",
    0x06: "Server Device Busy", 0x08: "Memory Parity Error",
    0x0A: "Gateway Path Unavailable", 0x0B: "Gateway Target Device Failed to Respond",
}
BROADCAST_UNIT = 0  # ch.2 "Composizione del frame": 0 = broadcast, 1..90 drives
MAX_READ_QUANTITY = 125  # ch.2 "Codice 03": quantity of registers 1 to 125 (0x7D)

MODBUS = "modbus"  # drive.fieldbus when c9 = 3


class ModbusDrive(Protocol):
    """What the PDU layer needs from a drive (devices.servo.drive.ServoDrive).

    ``write_parameter(0x3802, 0x0011)`` is the save command; ``fieldbus`` is the bus c9 chose
    at power-up.
    """

    @property
    def node_id(self) -> int: ...

    @property
    def responding(self) -> bool: ...

    def read_register(self, n: int) -> int: ...

    def write_register(self, n: int, value: int) -> None: ...

    def read_parameter(self, address: int) -> int: ...

    def write_parameter(self, address: int, value: int) -> None: ...

    def is_register(self, n: int) -> bool: ...

    def parameter_addresses(self) -> list[int]: ...

    @property
    def fieldbus(self) -> str: ...


# ---- outcomes --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Reply:
    """A normal response PDU (function code + data)."""

    pdu: bytes
    #: The write started a save to flash (mode -50, control word 0x20): the seed's first save
    #: method answers "at the end of the operation", so the server holds the reply until the
    #: drive answers again (ch.2 "Esempi", "Primo metodo di salvataggio").
    after_save: bool = False


@dataclass(frozen=True)
class Exception02:
    """Exception response 02 Illegal Data Address to ``function_code``."""

    function_code: int

    @property
    def pdu(self) -> bytes:
        return bytes((self.function_code | EXCEPTION_FLAG, ILLEGAL_DATA_ADDRESS))


@dataclass(frozen=True)
class Silence:
    """No reply at all; ``reason`` is for logs and tests only."""

    reason: str


Outcome = Reply | Exception02 | Silence


class _Discard(Exception):
    """Any error other than an illegal address: the drive drops the request."""


class _IllegalAddress(Exception):
    """Answered with exception 02."""


# ---- the line: which drive answers -----------------------------------------------------------
def serve_line(drives: Sequence[ModbusDrive], unit_id: int, pdu: bytes) -> Outcome:
    """Serve one request addressed to ``unit_id`` on a line holding ``drives``."""
    if unit_id == BROADCAST_UNIT:
        return _broadcast(drives, pdu)
    if unit_id > MODBUS_NODE_HIGH:
        # Reserved even if a drive's c7 got there (a CANopen node number kept across c9 = 3).
        return Silence(f"unit id {unit_id} is reserved (slaves are 1..{MODBUS_NODE_HIGH})")
    listening = [d for d in _on_line(drives) if d.node_id == unit_id]
    if not listening:
        return Silence(f"no drive answers unit id {unit_id}")
    if len(listening) > 1:
        # Two drives with one node number both answer and their replies collide on the line.
        return Silence(f"{len(listening)} drives share node number {unit_id}")
    return serve_pdu(listening[0], pdu)


def _broadcast(drives: Sequence[ModbusDrive], pdu: bytes) -> Silence:
    # ch.2: FC 06 and 16 may be broadcast ("la scrittura dello stesso parametro in tutti i drive
    # della rete"); FC 03 may not ("Con questa funzione non è ammesso il broadcast").
    if not pdu or pdu[0] not in (FC_WRITE_SINGLE_REGISTER, FC_WRITE_MULTIPLE_REGISTERS):
        return Silence("broadcast of a function that may not be broadcast")
    for drive in _on_line(drives):
        serve_pdu(drive, pdu)
    return Silence("broadcast: never answered")


def _on_line(drives: Sequence[ModbusDrive]) -> list[ModbusDrive]:
    """The drives that listen now: c9 = 3 at power-up (ch.2 "Configurazione della rete"),
    powered and not saving to flash."""
    return [d for d in drives if d.responding and d.fieldbus == MODBUS]


# ---- one drive -------------------------------------------------------------------------------
def serve_pdu(drive: ModbusDrive, pdu: bytes) -> Outcome:
    """Serve one request PDU on one drive; state is unchanged unless the outcome is a Reply."""
    handler = _HANDLERS.get(pdu[0]) if pdu else None
    if handler is None:
        return Silence(f"function code {pdu[:1].hex() or 'missing'} not implemented")
    try:
        return handler(drive, pdu)
    except _IllegalAddress as exc:
        logger.debug("exception 02: %s", exc)
        return Exception02(pdu[0])
    except _Discard as exc:
        logger.debug("request discarded: %s", exc)
        return Silence(str(exc))


class _Kind(Enum):
    PARAMETER = "parameter"
    REGISTER = "register"
    SAVE = "save command"
    NOTHING = "nothing"


@dataclass(frozen=True)
class _Target:
    kind: _Kind
    index: int  # parameter address or register number


def _locate(drive: ModbusDrive, address: int) -> _Target:
    """What a Modbus data address names on this drive, under its current address map."""
    if address == SAVE_ADDRESS:
        return _Target(_Kind.SAVE, address)
    if _siemens_map(drive):
        if address >= SIEMENS_REGISTER_BASE:
            return _register_target(drive, address - SIEMENS_REGISTER_BASE)
        if address >= SIEMENS_PARAMETER_BASE:
            return _parameter_target(drive, address - SIEMENS_PARAMETER_BASE)
        return _Target(_Kind.NOTHING, address)
    if address >= REGISTER_BASE:
        return _register_target(drive, address - REGISTER_BASE)
    return _parameter_target(drive, address)


def _siemens_map(drive: ModbusDrive) -> bool:
    try:
        return active_map(drive.read_parameter(E3_ADDRESS)) == SIEMENS
    except AccessError:
        return False


def _register_target(drive: ModbusDrive, n: int) -> _Target:
    return _Target(_Kind.REGISTER if drive.is_register(n) else _Kind.NOTHING, n)


def _parameter_target(drive: ModbusDrive, address: int) -> _Target:
    known = address in drive.parameter_addresses()
    return _Target(_Kind.PARAMETER if known else _Kind.NOTHING, address)


def _call(fn: Callable[[], int | None]) -> int | None:
    """Run one drive access, sorting its refusal into exception 02 or silence."""
    try:
        return fn()
    except AccessError as exc:
        if exc.kind == "address":
            raise _IllegalAddress(str(exc)) from None
        raise _Discard(f"{exc.kind}: {exc}") from None
    except CommandError as exc:  # e.g. powered off between two requests: no reply
        raise _Discard(str(exc)) from None


def _read(fn: Callable[[], int]) -> int:
    value = _call(fn)
    assert value is not None
    return value


def _u16(value: int) -> bytes:
    return (value & 0xFFFF).to_bytes(2, "big")


def _u32(value: int) -> bytes:
    return (value & 0xFFFFFFFF).to_bytes(4, "big")  # high word first (ch.2 "Codice 03")


def _sign_extend16(value: int) -> int:
    """ch.2 "Codice 06": the high 16 bits of the register take the sign of the low 16."""
    return value - 0x10000 if value & 0x8000 else value


# ---- FC 03 -----------------------------------------------------------------------------------
def _read_holding_registers(drive: ModbusDrive, pdu: bytes) -> Outcome:
    if len(pdu) != 5:
        raise _Discard(f"FC 03 request of {len(pdu)} bytes (5 expected)")
    address = int.from_bytes(pdu[1:3], "big")
    quantity = int.from_bytes(pdu[3:5], "big")
    if not 1 <= quantity <= MAX_READ_QUANTITY:
        raise _Discard(f"FC 03 quantity {quantity} outside 1..{MAX_READ_QUANTITY}")
    first = _locate(drive, address)
    if first.kind is _Kind.REGISTER:
        data = _read_register_block(drive, first.index, quantity)
    elif first.kind is _Kind.PARAMETER:
        data = _read_parameter_block(drive, first.index, quantity)
    else:
        raise _IllegalAddress(f"nothing readable at 0x{address:04X}")
    return Reply(bytes((FC_READ_HOLDING_REGISTERS, len(data))) + data)


def _read_register_block(drive: ModbusDrive, n: int, quantity: int) -> bytes:
    if quantity == 1:  # "Quantity of registers = 1": the 16 least significant bits
        return _u16(_read(lambda: drive.read_register(n)))
    if quantity % 2:
        # A 32-bit register is two words; an odd count would split one. The seed only shows
        # quantity 1 (low word) and 2 per register ("2 registri a 32 bit = 4 registri a 16 bit").
        raise _Discard(f"FC 03 odd quantity {quantity} on registers")
    numbers = range(n, n + quantity // 2)
    missing = [k for k in numbers if not drive.is_register(k)]
    if missing:
        raise _IllegalAddress(f"R{missing[0]} does not exist")
    return b"".join(_u32(_read(lambda k=k: drive.read_register(k))) for k in numbers)


def _read_parameter_block(drive: ModbusDrive, address: int, quantity: int) -> bytes:
    addresses = range(address, address + quantity)
    known = set(drive.parameter_addresses())
    missing = [a for a in addresses if a not in known]
    if missing:
        raise _IllegalAddress(f"no parameter at address {missing[0]}")
    return b"".join(_u16(_read(lambda a=a: drive.read_parameter(a))) for a in addresses)


# ---- FC 06 -----------------------------------------------------------------------------------
def _write_single_register(drive: ModbusDrive, pdu: bytes) -> Outcome:
    if len(pdu) != 5:
        raise _Discard(f"FC 06 request of {len(pdu)} bytes (5 expected)")
    address = int.from_bytes(pdu[1:3], "big")
    value = int.from_bytes(pdu[3:5], "big")
    target = _locate(drive, address)
    if target.kind is _Kind.SAVE:
        _save(drive, value)
        return Reply(pdu)
    if target.kind is _Kind.REGISTER:
        return _write_register(drive, target.index, _sign_extend16(value), pdu)
    if target.kind is _Kind.PARAMETER:
        _call(lambda: drive.write_parameter(target.index, value))
        return Reply(pdu)
    raise _IllegalAddress(f"nothing writable at 0x{address:04X}")


# ---- FC 16 -----------------------------------------------------------------------------------
def _write_multiple_registers(drive: ModbusDrive, pdu: bytes) -> Outcome:
    if len(pdu) < 6:
        raise _Discard(f"FC 16 request of {len(pdu)} bytes")
    address = int.from_bytes(pdu[1:3], "big")
    quantity = int.from_bytes(pdu[3:5], "big")
    byte_count = pdu[5]
    if quantity not in (1, 2):  # ch.2 "Codice 16": "al massimo due registri contigui"
        raise _Discard(f"FC 16 quantity {quantity} (1 or 2 only)")
    if byte_count != 2 * quantity or len(pdu) != 6 + byte_count:
        raise _Discard(f"FC 16 byte count {byte_count} / length {len(pdu)} for {quantity} words")
    words = [int.from_bytes(pdu[6 + 2 * i : 8 + 2 * i], "big") for i in range(quantity)]
    target = _locate(drive, address)
    echo = pdu[:5]  # the reply is the starting address and the quantity
    if target.kind is _Kind.SAVE:
        _save(drive, words[0] << 16 | words[1] if quantity == 2 else words[0])
        return Reply(echo)
    if target.kind is _Kind.REGISTER:
        value = (words[0] << 16 | words[1]) if quantity == 2 else _sign_extend16(words[0])
        return _write_register(drive, target.index, value, echo)
    if target.kind is _Kind.PARAMETER:
        _write_parameters(drive, target.index, words)
        return Reply(echo)
    raise _IllegalAddress(f"nothing writable at 0x{address:04X}")


def _write_parameters(drive: ModbusDrive, address: int, words: list[int]) -> None:
    """One parameter, or two contiguous ones written all-or-nothing."""
    known = set(drive.parameter_addresses())
    if any(address + i not in known for i in range(len(words))):
        raise _IllegalAddress(f"no parameter at {address}..{address + len(words) - 1}")
    before = [_read(lambda a=address + i: drive.read_parameter(a)) for i in range(len(words))]
    done = 0
    try:
        for i, word in enumerate(words):
            _call(lambda a=address + i, w=word: drive.write_parameter(a, w))
            done += 1
    except (_Discard, _IllegalAddress):
        for i in reversed(range(done)):  # undo the first word: the drive keeps its old state
            drive.write_parameter(address + i, before[i])
        raise


# ---- shared write paths ----------------------------------------------------------------------
def _write_register(drive: ModbusDrive, n: int, raw: int, reply: bytes) -> Reply:
    # The 32-bit pattern as on the wire; the drive reads it as signed where the register is.
    _call(lambda: drive.write_register(n, raw & 0xFFFF_FFFF))
    # Save method 1 (mode -50, control word 0x20) stops the drive answering; the reply of the
    # write that started it comes at the end of the save.
    return Reply(reply, after_save=not drive.responding)


def _save(drive: ModbusDrive, value: int) -> None:
    """0x0011 at 0x3802 saves; the drive refuses any other value (then: no reply)."""
    _call(lambda: drive.write_parameter(SAVE_ADDRESS, value))


_HANDLERS: dict[int, Callable[[ModbusDrive, bytes], Outcome]] = {
    FC_READ_HOLDING_REGISTERS: _read_holding_registers,
    FC_WRITE_SINGLE_REGISTER: _write_single_register,
    FC_WRITE_MULTIPLE_REGISTERS: _write_multiple_registers,
}
assert set(_HANDLERS) == set(IMPLEMENTED_FUNCTIONS), "the Codes tab reads IMPLEMENTED_FUNCTIONS"
