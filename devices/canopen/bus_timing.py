"""How long a CAN frame occupies the bus, and one bus line that frames queue for.

The drive's bit rate is parameter n1, read at power-up (seed 004 ch. 4 "Configurazione della
rete": n1 = 1..8 -> 10, 20, 50, 125, 250, 500, 800, 1000 kBaud). A classic CAN 2.0A data frame
is 47 bits of overhead (SOF, 11-bit identifier, RTR, IDE, r0, DLC, 15-bit CRC, delimiters, ACK,
EOF, 3 bits of intermission) plus 8 bits per data byte; bit stuffing adds at most one bit per
four in the stuffed part (SOF up to the CRC). We count that worst case, as bus-load tools do, so
an 8-byte frame takes 135 bit times: 135 us at 1 Mbit/s, 1.08 ms at 125 kbit/s.

:class:`CanLine` is the wire: one frame at a time, a waiting frame starts when the line is
free, and among the frames the transmitters offer at that instant the lowest identifier wins
arbitration. There are two transmitters: the node, whose waiting frames compete by identifier
(its highest-priority frame is always offered), and the rest of the bus (the master), whose
frames leave in the order it sent them (one transmit queue, as a master's driver keeps it). A
frame that started is never pre-empted. Both directions share the line: a master's request
must finish before the drive can see it, and the drive's answer then queues like any frame.
"""

from __future__ import annotations

import heapq
import itertools
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field

from devices.servo.parameters import CAN_KBAUD_BY_N1

OVERHEAD_BITS = 47  # SOF 1, id 11, RTR 1, IDE 1, r0 1, DLC 4, CRC 15+1, ACK 2, EOF 7, IFS 3
STUFFED_OVERHEAD_BITS = 34  # the part bit stuffing applies to: SOF .. CRC sequence
MAX_WAITING = 4096  # frames a line holds before it drops new ones (a babbling master)


def bitrate_of_n1(n1: int) -> int:
    """Bit/s of the n1 value (ch. 4 table); KeyError names nothing else: n1 is range-checked."""
    return CAN_KBAUD_BY_N1[n1] * 1000


def frame_bits(dlc: int, rtr: bool = False) -> int:
    """Bit times of a standard-identifier frame, worst-case stuffing included."""
    if not 0 <= dlc <= 8:
        raise ValueError(f"DLC {dlc} is outside 0..8")
    data_bits = 0 if rtr else 8 * dlc  # a remote frame carries a DLC but no data field
    stuffed = STUFFED_OVERHEAD_BITS + data_bits
    return OVERHEAD_BITS + data_bits + (stuffed - 1) // 4


def frame_time_us(dlc: int, bitrate: int, rtr: bool = False) -> int:
    """Microseconds the frame occupies a bus at ``bitrate`` bit/s (rounded up)."""
    return -(-frame_bits(dlc, rtr) * 1_000_000 // bitrate)


@dataclass(frozen=True)
class CanFrame:
    """One frame as the node sees it. ``t_us``: when it finished on the bus (simulated time)."""

    can_id: int
    data: bytes = b""
    rtr: bool = False
    dlc: int = -1  # remote frames: the requested length; -1 = len(data)
    t_us: int = 0
    rx: bool = True  # True: from the bus to the node; False: the node transmitted it

    @property
    def length(self) -> int:
        return len(self.data) if self.dlc < 0 else self.dlc


@dataclass(order=True)
class _Waiting:
    ready_us: int
    can_id: int
    seq: int
    frame: CanFrame = field(compare=False)


@dataclass
class CanLine:
    """The bus wire of one node: arbitration by identifier, one frame at a time."""

    bitrate: int
    busy_until_us: int = 0
    busy_us_total: int = 0
    _waiting: list[_Waiting] = field(default_factory=list)  # the node's frames (a heap)
    _incoming: deque[_Waiting] = field(default_factory=deque)  # the master's, in order
    _on_wire: tuple[int, CanFrame] | None = None  # (end time, frame)
    _seq: Iterator[int] = field(default_factory=itertools.count)
    dropped: int = 0

    def offer(self, frame: CanFrame, ready_us: int) -> bool:
        """Queue a frame that wants the bus from ``ready_us``; False when the line is full."""
        if len(self._waiting) + len(self._incoming) >= MAX_WAITING:
            self.dropped += 1
            return False
        waiting = _Waiting(ready_us, frame.can_id, next(self._seq), frame)
        if frame.rx:
            ready_us = max(ready_us, self._incoming[-1].ready_us) if self._incoming else ready_us
            waiting.ready_us = ready_us
            self._incoming.append(waiting)
        else:
            heapq.heappush(self._waiting, waiting)
        return True

    def duration_us(self, frame: CanFrame) -> int:
        return frame_time_us(frame.length, self.bitrate, frame.rtr)

    def next_done(self, now_us: int) -> CanFrame | None:
        """The next frame that finished by ``now_us``, stamped with its end time, or None.

        Call repeatedly: a frame that a handler queues at the end time of the previous one
        competes for the line from that instant.
        """
        if self._on_wire is None and not self._start_next(now_us):
            return None
        assert self._on_wire is not None
        end_us, frame = self._on_wire
        if end_us > now_us:
            return None
        self._on_wire = None
        return CanFrame(frame.can_id, frame.data, frame.rtr, frame.dlc, end_us, frame.rx)

    def _start_next(self, now_us: int) -> bool:
        firsts = [q[0].ready_us for q in (self._waiting, self._incoming) if q]
        if not firsts:
            return False
        start = max(self.busy_until_us, min(firsts))
        if start > now_us:
            return False
        # Arbitration at ``start``: the node offers its lowest identifier, the master the
        # head of its queue; the lower identifier wins.
        offers = []
        ready = [w for w in self._waiting if w.ready_us <= start]
        if ready:
            offers.append(min(ready, key=lambda w: (w.can_id, w.seq)))
        if self._incoming and self._incoming[0].ready_us <= start:
            offers.append(self._incoming[0])
        winner = min(offers, key=lambda w: (w.can_id, w.seq))
        if winner.frame.rx:
            self._incoming.popleft()
        else:
            self._waiting.remove(winner)
            heapq.heapify(self._waiting)
        duration = self.duration_us(winner.frame)
        self.busy_until_us = start + duration
        self.busy_us_total += duration
        self._on_wire = (self.busy_until_us, winner.frame)
        return True

    @property
    def idle(self) -> bool:
        """Nothing queued and nothing on the wire."""
        return not self._waiting and not self._incoming and self._on_wire is None

    @property
    def waiting(self) -> int:
        return len(self._waiting) + len(self._incoming) + (self._on_wire is not None)

    def clear(self) -> None:
        """Power off: whatever was queued or on the wire is lost."""
        self._waiting.clear()
        self._incoming.clear()
        self._on_wire = None
