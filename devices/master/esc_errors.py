"""Each slave's ESC error counters (0x0300-0x0313) and what a damaged cable does to them.

Seed 004 (drive manual, EtherCAT chapter, "Error Detection"): master and slaves check the FCS;
a slave that finds a checksum error does not correct it but counts it, so that the master can
locate the error. The ESC rules (ET1100 / ET1200 datasheet, ESC register description section
II 3.33-3.37, ETG.1000.4), as docs/ethercat-master.md "Damaged cable" writes them down:

- 0x0300 + 2*port: invalid frame counter (a frame with a bad FCS received on that port);
  0x0301 + 2*port: RX error counter (the PHY's RX_ER; a damaged cable here only spoils frames,
  so it stays 0 unless a test sets it);
- the first ESC that receives a corrupted frame counts it as invalid and marks it (a special
  FCS); every later ESC that receives the marked frame counts it in 0x0308 + port, the
  forwarded RX error counter;
- 0x030C, the ECAT processing unit error counter: every frame with a wrong FCS that passes the
  processing unit. In a line the unit sits after port 0 (the port order 0 -> unit -> 3 -> 1
  -> 2 -> 0): the forward direction passes it, the return direction (port 1 -> port 0) not;
- 0x0310 + port: lost link counter (only open ports count: a port whose link went down);
- each counter 8 bits, counting stops at 0xFF;
- a write to any of 0x0300-0x030B clears 0x0300-0x030B, one to 0x030C clears 0x030C, one to
  0x030D clears 0x030D, one to any of 0x0310-0x0313 clears the four (the value is ignored).

The line's ports: port 0 (IN) towards the master, port 1 (OUT) onwards.

A wire master's frames (docs/ethercat-wire.md "Damaged cable") go through the same
``run_frame`` in the wire process, with a generator seeded by ``frame_seed`` from the master's;
its counts come back to the model as batches that ``EscErrors.add`` adds.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Any

PORTS = 4
IN, OUT = 0, 1
TOP = 0xFF  # 8-bit counters: counting stops here
BASE = 0x0300
END = 0x0314  # 0x0300-0x0313
# (first, end) of each block a write clears as a whole (ESC register description).
CLEARED_TOGETHER = ((0x0300, 0x030C), (0x030C, 0x030D), (0x030D, 0x030E), (0x0310, 0x0314))


def _zeros() -> list[int]:
    return [0] * PORTS


@dataclass
class EscErrors:
    """One slave's counters, as its ESC holds them."""

    invalid: list[int] = field(default_factory=_zeros)  # 0x0300 + 2*port
    rx: list[int] = field(default_factory=_zeros)  # 0x0301 + 2*port
    forwarded: list[int] = field(default_factory=_zeros)  # 0x0308 + port
    epu: int = 0  # 0x030C
    pdi: int = 0  # 0x030D
    lost_link: list[int] = field(default_factory=_zeros)  # 0x0310 + port

    def registers(self) -> bytes:
        """0x0300-0x0313 as a master reads them (0x030E PDI error code and 0x030F: 0)."""
        out = bytearray(END - BASE)
        for port in range(PORTS):
            out[2 * port], out[2 * port + 1] = self.invalid[port], self.rx[port]
            out[0x08 + port], out[0x10 + port] = self.forwarded[port], self.lost_link[port]
        out[0x0C], out[0x0D] = self.epu, self.pdi
        return bytes(out)

    @classmethod
    def from_registers(cls, data: bytes) -> EscErrors:
        """The counters ``registers`` wrote (0x030E / 0x030F ignored)."""
        data = bytes(data).ljust(END - BASE, b"\0")
        return cls(invalid=list(data[0:8:2]), rx=list(data[1:8:2]),
                   forwarded=list(data[0x08:0x0C]), epu=data[0x0C], pdi=data[0x0D],
                   lost_link=list(data[0x10:0x14]))

    def add(self, other: EscErrors) -> None:
        """``other``'s counts counted here too, each stopping at 0xFF: the same as counting
        them one by one (another process's frames, counted there)."""
        for mine, theirs in ((self.invalid, other.invalid), (self.rx, other.rx),
                             (self.forwarded, other.forwarded),
                             (self.lost_link, other.lost_link)):
            for port in range(PORTS):
                mine[port] = min(TOP, mine[port] + theirs[port])
        self.epu = min(TOP, self.epu + other.epu)
        self.pdi = min(TOP, self.pdi + other.pdi)

    def counted(self) -> bool:
        return any(self.registers())

    def write(self, ado: int, length: int) -> bool:
        """A master's write to [ado, ado + length): the blocks it touches are cleared.
        True when the write touched the counters."""
        end = ado + length
        touched = False
        for first, last in CLEARED_TOGETHER:
            if ado < last and end > first:
                touched = True
                self._clear(first)
        return touched

    def clear(self) -> None:
        """Every counter (the ESC's power-on)."""
        for first, _last in CLEARED_TOGETHER:
            self._clear(first)

    def _clear(self, first: int) -> None:
        if first == 0x0300:
            self.invalid, self.rx, self.forwarded = _zeros(), _zeros(), _zeros()
        elif first == 0x030C:
            self.epu = 0
        elif first == 0x030D:
            self.pdi = 0
        else:
            self.lost_link = _zeros()

    def lose_link(self, port: int) -> None:
        self.lost_link[port] = min(TOP, self.lost_link[port] + 1)

    def snapshot(self) -> dict[str, Any]:
        """Plain data: the line's two ports and the processing unit."""
        return {"invalid": self.invalid[:2], "rx": self.rx[:2],
                "forwarded": self.forwarded[:2], "lost_link": self.lost_link[:2],
                "epu": self.epu}


def _bump(counts: list[int], port: int) -> None:
    if counts[port] < TOP:
        counts[port] += 1


def frame_seed(master_rng: random.Random) -> int:
    """The seed of the generator that draws a wire master's crossings (run_frame's ``rng`` in
    the wire process): from a copy of the master's generator, so it follows the rig's seed
    while the master's own sequence (its DC measurement) keeps every draw."""
    copy = random.Random()
    copy.setstate(master_rng.getstate())
    return copy.getrandbits(64)


def run_frame(errors: list[EscErrors], last: int, damaged: dict[int, float],
              rng: random.Random) -> bool:
    """One frame out to position ``last`` (the last slave it reaches) and back, through the
    damaged cables (cable -> share of the crossings it spoils); True: the frame comes back
    spoiled (the master drops it). Cable N joins position N-1's OUT (the master for N = 0) to
    position N's IN; one draw per crossing, forward in line order, then back."""
    marked = False
    for p in range(last + 1):  # forward: each slave receives on its IN port
        esc = errors[p]
        share = damaged.get(p)
        if share is not None and rng.random() < share and not marked:
            marked = True
            _bump(esc.invalid, IN)
        elif marked:
            _bump(esc.forwarded, IN)
        if marked and esc.epu < TOP:
            esc.epu += 1
    for p in range(last, -1, -1):  # back: cable p carries it to position p-1's OUT port
        share = damaged.get(p)
        spoiled = share is not None and rng.random() < share
        if p == 0:
            return marked or spoiled  # the master checks the FCS
        esc = errors[p - 1]
        if spoiled and not marked:
            marked = True
            _bump(esc.invalid, OUT)
        elif marked:
            _bump(esc.forwarded, OUT)
    return marked
