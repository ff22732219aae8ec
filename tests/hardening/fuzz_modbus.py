"""Modbus request PDUs for fuzzing, and the oracle that judges the drive's answer to each.

The generator (a seeded ``random.Random``) mixes well-formed requests at the addresses that
matter (parameters, the save command 0x3802, R00..R133 at 0x8000, the Siemens map of e3 = 9 at
40001 / 44097, the edges around them) with valid function codes of bad lengths, quantities and
byte counts, truncated and mutated frames, and garbage.

The oracle is the rule set of docs/modbus.md (seed 004 ch.2 "Codici funzione", "Eccezioni"):
an answer is a correct response, exception 02, or silence; anything rejected (exception 02 or
silence) leaves every drive as it was; a broadcast (unit 0) is never answered.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from app.modbus.pdu import Exception02, Outcome, Reply, Silence
from devices.servo.drive import ServoDrive

FC03, FC06, FC16 = 0x03, 0x06, 0x10
E3_ADDRESS, E3_SIEMENS = 58, 9
SIEMENS_PARAMETER_BASE, SIEMENS_REGISTER_BASE = 40001, 44097
REGISTER_BASE = 0x8000
ADDRESSES = (0, 1, 2, 3, 20, 22, 23, 34, 35, 40, 54, 58, 67, 81, 90, 99, 100, 0x3801, 0x3802,
             0x3803, 0x7FFF, 0x8000, 0x8001, 0x8002, 0x8005, 0x8006, 0x8084, 0x8085, 0x8086,
             0x9C40, 0x9C41, 0x9C42, 0x9C73, 0x9CA4, 0xAC40, 0xAC41, 0xAC42, 0xAC4A, 0xACC6,
             0xACC7, 0xFFFF)
VALUES = (0, 1, 2, 3, 5, 6, 7, 9, 0x0F, 0x11, 0x20, 0x40, 0x80, 0xFF, 0x7FFF, 0x8000,
          0xFFCE, 0xFFFF)  # 0xFFCE = -50: mode "save/load" on R01
QUANTITIES = (0, 1, 2, 3, 4, 8, 124, 125, 126, 0x7D00, 0xFFFF)

State = tuple[Any, ...]


def drive_state(drive: ServoDrive) -> State:
    """Everything a request could change: the snapshot plus the raw parameter and register
    tables. Nothing steps between two captures, so no field varies with time in between."""
    return drive.snapshot(), dict(drive.params), dict(drive.regs)


def line_state(drives: Sequence[ServoDrive]) -> list[State]:
    return [drive_state(d) for d in drives]


# ---- the generator ---------------------------------------------------------------------------
def _u16(value: int) -> bytes:
    return (value & 0xFFFF).to_bytes(2, "big")


def _address(rng: random.Random) -> int:
    if rng.random() < 0.8:
        return min(0xFFFF, max(0, rng.choice(ADDRESSES) + rng.choice((0, 0, 0, -1, 1))))
    return rng.randrange(0x10000)


def _value(rng: random.Random) -> int:
    return rng.choice(VALUES) if rng.random() < 0.7 else rng.randrange(0x10000)


def well_formed(rng: random.Random) -> bytes:
    fc = rng.choice((FC03, FC03, FC06, FC16))
    if fc == FC03:
        quantity = rng.choice(QUANTITIES) if rng.random() < 0.3 else rng.choice((1, 2, 4, 6))
        return bytes((FC03,)) + _u16(_address(rng)) + _u16(quantity)
    if fc == FC06:
        return bytes((FC06,)) + _u16(_address(rng)) + _u16(_value(rng))
    quantity = rng.choice((1, 2))
    words = b"".join(_u16(_value(rng)) for _ in range(quantity))
    return bytes((FC16,)) + _u16(_address(rng)) + _u16(quantity) + bytes((2 * quantity,)) + words


def _bad_length(rng: random.Random) -> bytes:
    frame = well_formed(rng)
    if rng.random() < 0.5:
        return frame + bytes(rng.randrange(256) for _ in range(rng.randint(1, 6)))
    return frame[:-rng.randint(1, len(frame) - 1)]


def _bad_fc16(rng: random.Random) -> bytes:
    quantity = rng.choice((0, 1, 2, 3, 4, 123, 0xFFFF))
    byte_count = rng.choice((0, 1, 2, 3, 4, 6, 246, 255, 2 * quantity & 0xFF))
    data = bytes(rng.randrange(256) for _ in range(rng.choice((0, 1, 2, 3, 4, 5, 8))))
    return bytes((FC16,)) + _u16(_address(rng)) + _u16(quantity) + bytes((byte_count,)) + data


def _truncated(rng: random.Random) -> bytes:
    frame = well_formed(rng)
    return frame[:rng.randrange(len(frame))]


def _mutated(rng: random.Random) -> bytes:
    frame = bytearray(well_formed(rng))
    for _ in range(rng.randint(1, 3)):
        i = rng.randrange(len(frame))
        if rng.random() < 0.5:
            frame[i] ^= 1 << rng.randrange(8)
        else:
            frame[i] = rng.randrange(256)
    return bytes(frame)


def _garbage(rng: random.Random) -> bytes:
    return bytes(rng.randrange(256) for _ in range(rng.choice((0, 1, 2, 5, 6, 7, 12, 253))))


KINDS: tuple[tuple[str, Callable[[random.Random], bytes], int], ...] = (
    ("well_formed", well_formed, 35), ("bad_length", _bad_length, 15),
    ("bad_fc16", _bad_fc16, 10), ("truncated", _truncated, 10), ("mutated", _mutated, 20),
    ("garbage", _garbage, 10),
)


def unit_id(rng: random.Random, units: Sequence[int]) -> int:
    roll = rng.random()
    if roll < 0.75:
        return rng.choice(units)
    if roll < 0.85:
        return 0  # broadcast
    return rng.randrange(256)


def requests(rng: random.Random, n: int, units: Sequence[int]) -> Iterator[tuple[int, bytes]]:
    """``n`` (unit id, PDU) pairs."""
    makers = [maker for _name, maker, weight in KINDS for _ in range(weight)]
    for _ in range(n):
        yield unit_id(rng, units), rng.choice(makers)(rng)


# ---- the oracle ------------------------------------------------------------------------------
def length_ok(pdu: bytes) -> bool:
    """The request has the exact length its function code asks for (ch.2 "Codice 03/06/16")."""
    if len(pdu) < 1 or pdu[0] not in (FC03, FC06, FC16):
        return False
    if pdu[0] in (FC03, FC06):
        return len(pdu) == 5
    return len(pdu) >= 6 and pdu[3:5] in (b"\0\1", b"\0\2") and pdu[5] == 2 * pdu[4] \
        and len(pdu) == 6 + pdu[5]


def expected_read(drive: ServoDrive, address: int, quantity: int) -> bytes | None:
    """The data of a correct FC 03 response, from the address table of docs/modbus.md."""
    if drive.read_parameter(E3_ADDRESS) == E3_SIEMENS:
        if address >= SIEMENS_REGISTER_BASE:
            register, parameter = address - SIEMENS_REGISTER_BASE, None
        elif address >= SIEMENS_PARAMETER_BASE:
            register, parameter = None, address - SIEMENS_PARAMETER_BASE
        else:
            return None
    elif address >= REGISTER_BASE:
        register, parameter = address - REGISTER_BASE, None
    else:
        register, parameter = None, address
    if register is not None:
        if quantity == 1:
            return _u16(drive.read_register(register))
        return b"".join((drive.read_register(n) & 0xFFFF_FFFF).to_bytes(4, "big")
                        for n in range(register, register + quantity // 2))
    assert parameter is not None
    return b"".join(_u16(drive.read_parameter(a)) for a in range(parameter, parameter + quantity))


def judge(drives: Sequence[ServoDrive], unit: int, pdu: bytes, outcome: Outcome,
          before: list[State]) -> str | None:
    """Why ``outcome`` is wrong for this request (None: it is right)."""
    after = line_state(drives)
    listening = [d for d, (snap, _p, _r) in zip(drives, before, strict=True)
                 if snap["node_id"] == unit and snap["responding"] and snap["fieldbus"] == "modbus"]
    if isinstance(outcome, Silence):
        if unit == 0 and length_ok(pdu) and pdu[0] in (FC06, FC16):
            return None  # a broadcast write is applied and never answered
        return None if after == before else f"state changed by a request without reply " \
                                             f"({outcome.reason})"
    if unit == 0:
        return "a broadcast was answered"
    if len(listening) != 1:
        return f"answered for unit {unit}, held by {len(listening)} listening drives"
    if isinstance(outcome, Exception02):
        if not length_ok(pdu) or outcome.function_code != pdu[0]:
            return "exception 02 to a request of the wrong length or for another function"
        if pdu[0] == FC03 and not 1 <= int.from_bytes(pdu[3:5], "big") <= 125:
            return "exception 02 to a quantity outside 1..125 (must be silence)"
        return None if after == before else "state changed by a request answered with 02"
    if not isinstance(outcome, Reply):
        return f"unknown outcome {outcome!r}"
    return _judge_reply(listening[0], pdu, outcome.pdu)


def _judge_reply(drive: ServoDrive, pdu: bytes, reply: bytes) -> str | None:
    if not length_ok(pdu):
        return f"a reply to a request of the wrong length: {pdu.hex(' ')}"
    if pdu[0] == FC03:
        address, quantity = int.from_bytes(pdu[1:3], "big"), int.from_bytes(pdu[3:5], "big")
        data = expected_read(drive, address, quantity)
        if data is None or reply != bytes((FC03, len(data))) + data or \
                len(data) != 2 * quantity:
            return f"FC 03 reply {reply.hex(' ')} (expected data {data!r})"
        return None
    if pdu[0] == FC06:
        return None if reply == pdu else f"FC 06 reply {reply.hex(' ')} is not the echo"
    return None if reply == pdu[:5] else f"FC 16 reply {reply.hex(' ')} is not addr + quantity"
