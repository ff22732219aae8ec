"""The steady step's sync part is ``cycles_until`` without its list (docs/trscat.md "Step cost").

``SyncUnit.take_one_sync0`` stands for ``cycles_until`` in the usual DC-SYNC cycle: one SYNC0
since the last step, taking the one frame that came at least the calc + copy time before it
(seed 001 §9.1.1, §9.3.1 0x1C32:6), the SM-event-missed counter 0x1C32:11 reset (§9.3.7). It
must either do exactly what ``cycles_until`` does and answer that SYNC0's time, or change
nothing. Random sync units around the edges (a frame at the deadline, SYNC0 due exactly now,
two SYNC0s in one step, SYNC0 lost, no cycle, not running) compare the two.
"""

from __future__ import annotations

import copy
import random
from typing import Any

from devices.trscat.sync import CALC_COPY_US, SYNC0_ACTIVE, SyncUnit


def random_unit(rng: random.Random) -> tuple[SyncUnit, int]:
    unit = SyncUnit()
    cycle_us = rng.choice((500, 1000, 1000, 2000, 150_000))
    unit.configure(rng.choice((SYNC0_ACTIVE, SYNC0_ACTIVE, SYNC0_ACTIVE, 0)), cycle_us * 1000,
                   0, now_us=0)
    unit.running = rng.random() < 0.9
    t = unit.next_sync0_us = rng.randrange(0, 10_000, 100)
    near = (t - cycle_us, t - CALC_COPY_US - 1, t - CALC_COPY_US, t - CALC_COPY_US + 1, t - 1, t)
    unit.arrivals = [rng.choice(near) for _ in range(rng.choice((0, 1, 1, 1, 1, 2, 3)))]
    unit.sync0_lost = rng.random() < 0.1
    unit.sm_missed = rng.choice((0, 0, 1, 2, 3))
    unit.without_sync0 = rng.choice((0, 0, 1, 3))
    unit.sync0_seen = rng.random() < 0.5
    now = t + rng.choice((-1000, -1, 0, 0, 1, cycle_us - 1, cycle_us, cycle_us + 1, 2 * cycle_us))
    return unit, now


def state(unit: SyncUnit) -> dict[str, Any]:
    return dict(vars(unit))


def test_take_one_sync0_is_cycles_until_or_nothing() -> None:
    rng = random.Random(7)
    taken = declined = 0
    for _ in range(20_000):
        unit, now = random_unit(rng)
        other, before = copy.deepcopy(unit), state(unit)
        t = unit.take_one_sync0(now)
        if t is None:
            assert state(unit) == before  # declined: cycles_until is left the whole case
            declined += 1
            continue
        assert list(other.cycles_until(now)) == [(t, True)]
        assert state(unit) == state(other)
        taken += 1
    assert taken > 1000 and declined > 1000  # both ways were tried


def test_a_frame_after_the_deadline_is_not_steady() -> None:
    """§9.3.1 0x1C32:6: a frame less than the calc + copy time before SYNC0 waits for the
    next one; the short way declines it (cycles_until counts the SYNC0 as missed)."""
    unit = SyncUnit()
    unit.configure(SYNC0_ACTIVE, 1_000_000, 0, now_us=0)
    unit.running, unit.next_sync0_us = True, 5000
    unit.arrivals = [5000 - CALC_COPY_US + 1]
    assert unit.take_one_sync0(5000) is None
    unit.arrivals = [5000 - CALC_COPY_US]
    unit.sm_missed = 2
    assert unit.take_one_sync0(5000) == 5000
    assert (unit.arrivals, unit.sm_missed, unit.next_sync0_us) == ([], 0, 6000)
