"""Process B's side of a damaged cable: the model's damage applied to the wire master's frames.

What a damaged cable does is the model's (devices/master/esc_errors.py ``run_frame``: which
crossings it spoils, which ESC counters that moves); A sends the damaged cables and the seed
(``("damage", {cable: share}, seed)``) and B runs every frame it receives through
``run_frame`` before answering it. A spoiled frame is not answered (its FCS is wrong: the
master's NIC drops it), as the built-in master loses it.

The counters stay the model's: B sends what the frames added as batches (``esc_counts``, at
most every 10 ms) and A answers with the model's registers and the last batch they include
(``esc_errors``, seq). What a master reads at 0x0300-0x0313 is the model's answer plus the
batches it does not include yet plus what is not sent yet, so each count shows at once and
once (``WireCounters``).
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING

from devices.master.esc_errors import EscErrors, run_frame

if TYPE_CHECKING:
    from app.ethercat_wire.esc import Esc


class WireCounters:
    """One ESC's 0x0300-0x0313: the model's, and what this process counted on top of it."""

    def __init__(self) -> None:
        self.model = EscErrors()  # as A last sent them
        self.sent: list[tuple[int, EscErrors]] = []  # batches A had not applied then
        self.counting = EscErrors()  # since the last batch

    def registers(self) -> bytes:
        shown = EscErrors.from_registers(self.model.registers())
        for _seq, batch in self.sent:
            shown.add(batch)
        shown.add(self.counting)
        return shown.registers()

    def from_model(self, data: bytes, seq: int) -> None:
        self.model = EscErrors.from_registers(data)
        self.sent = [(s, batch) for s, batch in self.sent if s > seq]

    def write(self, ado: int, length: int) -> None:
        """A master's write: each block it touches cleared here, in the batches the model has
        not applied and in what is not sent (A clears the model's after the batches sent)."""
        self.model.write(ado, length)
        for _seq, batch in self.sent:
            batch.write(ado, length)
        self.counting.write(ado, length)

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
        self.rng = random.Random(0)
        self.seq = 0  # the last batch taken
        self.spoiled = 0  # frames lost to it since B started

    def set(self, shares: dict[int, float], seed: int) -> None:
        self.shares = {int(cable): float(share) for cable, share in shares.items()}
        if seed != self.seed:  # a new rig (A attached again): its own sequence
            self.seed, self.rng = seed, random.Random(seed)

    def spoils(self, visible: list[Esc]) -> bool:
        """This frame through the damaged cables, out to the last visible slave and back (as
        the built-in master's: run_frame); True: it comes back spoiled, not to be answered."""
        if not run_frame([esc.counters.counting for esc in visible], len(visible) - 1,
                         self.shares, self.rng):
            return False
        self.spoiled += 1
        for esc in visible:  # counted on a spoiled frame only: a master reads them at once
            esc.show_error_counters()
        return True

    def take(self, escs: list[Esc]) -> tuple[int, dict[int, bytes]] | None:
        """The next batch for A: (seq, {position: counts since the last batch})."""
        seq = self.seq + 1
        counts = {}
        for esc in escs:
            data = esc.counters.take(seq)
            if data is not None:
                counts[esc.position] = data
        if not counts:
            return None
        self.seq = seq
        return seq, counts
