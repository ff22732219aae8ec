"""Process B's side of a damaged cable: the model's damage applied to the wire master's frames.

What a damaged cable does is the model's (devices/master/esc_errors.py ``run_frame``: which
crossings it spoils, which ESC counters that moves); A sends the damaged cables and the seed
(``("damage", {cable: share}, seed)``) and B runs every frame it receives through
``run_frame`` before answering it. A spoiled frame is not answered (its FCS is wrong: the
master's NIC drops it), as the built-in master loses it.

The counters stay the model's: B sends what the frames added as batches (``esc_counts``, at
most every 10 ms) and A answers with the model's registers and the last batch they include
(``esc_errors``, seq). A master's write clears B's copy at once and goes to A numbered in the
same sequence as the batches (``esc_errors_write``, ..., seq); A acknowledges its number in
its answer. What a master reads at 0x0300-0x0313 is the model's answer with the writes it does
not include yet applied again, plus the batches it does not include yet, plus what is not sent
yet, so each count shows at once and once and a cleared one does not come back
(``WireCounters``).
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING

from devices.master.esc_errors import EscErrors, run_frame

if TYPE_CHECKING:
    from app.ethercat_wire.esc import Esc


class Numbers:
    """One sequence for the batches of counts and the master's writes, numbered in the order B
    sends them to A (A handles them in that order: its answer tagged n includes every batch
    and write numbered up to n)."""

    def __init__(self) -> None:
        self.last = 0

    def next(self) -> int:
        self.last += 1
        return self.last


class WireCounters:
    """One ESC's 0x0300-0x0313: the model's, and what this process counted on top of it."""

    def __init__(self, numbers: Numbers | None = None) -> None:
        self.numbers = numbers or Numbers()  # the line's (Line binds them)
        self.model = EscErrors()  # as A last sent them
        self.sent: list[tuple[int, EscErrors]] = []  # batches A had not applied then
        self.writes: list[tuple[int, int, int]] = []  # (seq, ado, length) A had not applied
        self.counting = EscErrors()  # since the last batch

    def registers(self) -> bytes:
        shown = EscErrors.from_registers(self.model.registers())
        for _seq, batch in self.sent:
            shown.add(batch)
        shown.add(self.counting)
        return shown.registers()

    def from_model(self, data: bytes, seq: int) -> None:
        """A's counters, which include the batches and writes numbered up to ``seq``: the
        master's later writes clear them again (A answers a batch before it has seen a write
        sent after it: what the master cleared must not come back meanwhile)."""
        self.model = EscErrors.from_registers(data)
        self.sent = [(s, batch) for s, batch in self.sent if s > seq]
        self.writes = [w for w in self.writes if w[0] > seq]
        for _seq, ado, length in self.writes:
            self.model.write(ado, length)

    def write(self, ado: int, length: int) -> int:
        """A master's write: each block it touches cleared here, in the batches the model has
        not applied and in what is not sent (A clears the model's after the batches sent).
        Returns its number, for A to acknowledge."""
        seq = self.numbers.next()
        self.writes.append((seq, ado, length))
        self.model.write(ado, length)
        for _seq, batch in self.sent:
            batch.write(ado, length)
        self.counting.write(ado, length)
        return seq

    def new_run(self) -> None:
        """A scenario load (A's new run): what this process counted and the fresh model has
        not taken belongs to the old run. The writes stay: A takes them into the fresh model."""
        self.sent, self.counting = [], EscErrors()

    def take(self, seq: int) -> bytes | None:
        """What was counted since the last batch, now batch ``seq``; None: nothing."""
        if not self.counting.counted():
            return None
        batch, self.counting = self.counting, EscErrors()
        self.sent.append((seq, batch))
        return batch.registers()


class Damage:
    """The damaged cables as the model last said, and the generator of their crossings."""

    def __init__(self) -> None:
        self.shares: dict[int, float] = {}
        self.seed: int | None = None
        self.run: int | None = None  # A's run (the rig's scenario loads) of the last "damage"
        self.rng = random.Random(0)
        self.numbers = Numbers()  # the batches' and the master's writes' (WireCounters)
        self.spoiled = 0  # frames lost to it in this run

    def set(self, shares: dict[int, float], seed: int, run: int) -> bool:
        """True: a new run (a scenario load; the seed may be the same): the crossings start
        again from the seed."""
        self.shares = {int(cable): float(share) for cable, share in shares.items()}
        if (seed, run) == (self.seed, self.run):
            return False
        self.seed, self.run, self.rng = seed, run, random.Random(seed)
        self.spoiled = 0
        return True

    def spoils(self, path: list[Esc]) -> bool:
        """This frame through the damaged cables, out to the last slave on its path (answering
        or not: Line.path) and back (as the built-in master's: run_frame); True: it comes back
        spoiled, not to be answered."""
        if not run_frame([esc.counters.counting for esc in path], len(path) - 1,
                         self.shares, self.rng):
            return False
        self.spoiled += 1
        for esc in path:  # counted on a spoiled frame only: a master reads them at once
            esc.show_error_counters()
        return True

    def take(self, escs: list[Esc]) -> tuple[int, dict[int, bytes]] | None:
        """The next batch for A: (seq, {position: counts since the last batch})."""
        seq = self.numbers.last + 1
        counts = {}
        for esc in escs:
            data = esc.counters.take(seq)
            if data is not None:
                counts[esc.position] = data
        if not counts:
            return None
        self.numbers.last = seq
        return seq, counts
