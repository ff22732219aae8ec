"""Modbus request PDUs for fuzzing, and the oracle that judges the drive's answer to each.

The generator (a seeded ``random.Random``) mixes well-formed requests at the addresses that
matter (parameters, the save command 0x3802, R00..R133 at 0x8000, the Siemens map of e3 = 9 at
40001 / 44097, the edges around them) with valid function codes of bad lengths, quantities and
byte counts, truncated and mutated frames, and garbage.

The oracle that judges each answer (what the line owes a request, worked out without the
code under test) is in modbus_oracle.py; ``judge`` and ``line_state`` are re-exported here.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Iterator, Sequence

from modbus_oracle import FC03, FC06, FC16, judge, line_state

__all__ = ["FC03", "FC06", "FC16", "judge", "line_state", "requests", "well_formed"]

ADDRESSES = (0, 1, 2, 3, 20, 22, 23, 34, 35, 40, 54, 58, 67, 81, 90, 99, 100, 0x3801, 0x3802,
             0x3803, 0x7FFF, 0x8000, 0x8001, 0x8002, 0x8005, 0x8006, 0x8084, 0x8085, 0x8086,
             0x9C40, 0x9C41, 0x9C42, 0x9C73, 0x9CA4, 0xAC40, 0xAC41, 0xAC42, 0xAC4A, 0xACC6,
             0xACC7, 0xFFFF)
VALUES = (0, 1, 2, 3, 5, 6, 7, 9, 0x0F, 0x11, 0x20, 0x40, 0x80, 0xFF, 0x7FFF, 0x8000,
          0xFFCE, 0xFFFF)  # 0xFFCE = -50: mode "save/load" on R01
QUANTITIES = (0, 1, 2, 3, 4, 8, 124, 125, 126, 0x7D00, 0xFFFF)


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
