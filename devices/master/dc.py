"""The master's distributed-clock management (seed 003): states, transitions, faults.

Seed 003 names five phases: IDLE (the master clock is independent of the slaves),
SYNCHRONIZING (preliminary measurements), WAITING_START_TIME (synchronised, waiting for the
first instant the slaves do I/O), COMPENSATING (tracking the network clock; slaves normally in
OP) and NOT_SYNCHRONIZED (the master cannot follow the network clock: every DC slave goes to
SAFEOP). The transitions are the table :data:`DC_TRANSITIONS`; the triggers are computed by
:meth:`DcUnit.step` from the line (link, DC slaves in SAFEOP/OP) and the deviation between the
master clock and the reference clock (the first DC slave). FieldRig's numbers (measurement
time, deviations) are in docs/ethercat-master.md.
"""

from __future__ import annotations

import enum
import random
from dataclasses import dataclass

SYNC_MEASURE_US = 100_000  # FieldRig: SYNCHRONIZING lasts 100 ms of drift measurements
START_DELAY_US = 100_000  # FieldRig: START_TIME = 100 ms after the DC slaves reached SAFEOP
DEFAULT_WINDOW_NS = 1_000  # the mapping file's <DcSyncWindow> default (ns)
NOISE_NS = 40  # FieldRig: healthy deviation, +- 40 ns around 0
DRIFT_NS_PER_MS = 25  # FieldRig: a drifting clock leaves the window in 40 ms (1 us window)
JITTER_FACTOR = 5  # FieldRig: jitter fault: +- 5 windows
RESYNC_AFTER_US = 500_000  # FieldRig: NOT_SYNCHRONIZED, fault gone -> measure again after
OUT_OF_WINDOW_CYCLES = 5  # FieldRig: consecutive cycles outside the window before giving up
LOCK_CYCLES = 5  # FieldRig: consecutive cycles inside the window to count as synced
NOISE_SPAN = 2 * NOISE_NS + 1  # the healthy deviation's values, -NOISE_NS .. NOISE_NS


def draw(rng: random.Random, low: int, span: int) -> int:
    """``rng.randrange(low, low + span)`` for ints, span > 0, one call instead of three.

    CPython's randrange (Lib/random.py, 3.11 and 3.12) turns integer arguments with step 1 into
    ``istart + self._randbelow(width)``; this makes that call directly: the same draw from the
    same stream, for every Random whatever its ``_randbelow`` (tests/devices/master/
    test_master_dc.py compares the two streams).
    """
    return low + rng._randbelow(span)


class DcState(enum.Enum):
    IDLE = "IDLE"
    SYNCHRONIZING = "SYNCHRONIZING"
    WAITING_START_TIME = "WAITING_START_TIME"
    COMPENSATING = "COMPENSATING"
    NOT_SYNCHRONIZED = "NOT_SYNCHRONIZED"


# Each phase in seed 003's words (the Codes tab reads them, app/decoder_states.py).
DC_STATE_TEXT: dict[DcState, str] = {
    DcState.IDLE: "the master clock is completely independent from the slaves",
    DcState.SYNCHRONIZING: "the master is making preliminary measurements to synchronize with "
                           "the slaves",
    DcState.WAITING_START_TIME: "the master has synced with the slaves and waits for the "
                                "START_TIME, the first time the slaves implement I/O",
    DcState.COMPENSATING: "the master clock is synchronous with the slaves' and START_TIME has "
                          "passed: the master is constantly tracking the clocks of the network, "
                          "typically all slaves are in OP",
    DcState.NOT_SYNCHRONIZED: "the master fails to follow the network clock: all the slaves "
                              "involved go to the SAFE_OP state",
}


class DcTrigger(enum.Enum):
    LINK_UP = "link_up"  # link seen and the line has DC slaves
    LINK_DOWN = "link_down"  # no link, or no DC slave on the line any more
    MEASURED = "measured"  # the preliminary measurements are done, inside the window
    START_TIME = "start_time"  # START_TIME passed with the DC slaves in SAFEOP / OP
    OUT_OF_WINDOW = "out_of_window"  # deviation over the sync window, or SYNC0 lost
    FAULT_GONE = "fault_gone"  # NOT_SYNCHRONIZED long enough with the cause gone


DC_TRANSITIONS: dict[tuple[DcState, DcTrigger], DcState] = {
    (DcState.IDLE, DcTrigger.LINK_UP): DcState.SYNCHRONIZING,
    (DcState.SYNCHRONIZING, DcTrigger.MEASURED): DcState.WAITING_START_TIME,
    # Seed 003 NOT_SYNCHRONIZED: "if for any reason the master fails to follow the network
    # clock" - also when it cannot get into the window while measuring (docs/ethercat-master.md).
    (DcState.SYNCHRONIZING, DcTrigger.OUT_OF_WINDOW): DcState.NOT_SYNCHRONIZED,
    (DcState.WAITING_START_TIME, DcTrigger.START_TIME): DcState.COMPENSATING,
    (DcState.WAITING_START_TIME, DcTrigger.OUT_OF_WINDOW): DcState.NOT_SYNCHRONIZED,
    (DcState.COMPENSATING, DcTrigger.OUT_OF_WINDOW): DcState.NOT_SYNCHRONIZED,
    (DcState.NOT_SYNCHRONIZED, DcTrigger.FAULT_GONE): DcState.SYNCHRONIZING,
    (DcState.SYNCHRONIZING, DcTrigger.LINK_DOWN): DcState.IDLE,
    (DcState.WAITING_START_TIME, DcTrigger.LINK_DOWN): DcState.IDLE,
    (DcState.COMPENSATING, DcTrigger.LINK_DOWN): DcState.IDLE,
    (DcState.NOT_SYNCHRONIZED, DcTrigger.LINK_DOWN): DcState.IDLE,
}

DC_FAULTS = ("drift", "jitter", "sync0_lost")


@dataclass(slots=True)  # slots: as devices/esm.py's Esm (the master reads its state every step)
class DcUnit:
    window_ns: int = DEFAULT_WINDOW_NS
    state: DcState = DcState.IDLE
    fault: str | None = None
    deviation_ns: int = 0
    since_us: int = 0  # when the present state was entered
    start_time_us: int | None = None  # START_TIME once the DC slaves are in SAFEOP
    outside: int = 0  # consecutive steps outside the sync window
    inside: int = 0  # SYNCHRONIZING: consecutive steps inside the sync window

    def out_of_window(self) -> bool:
        return self.fault == "sync0_lost" or abs(self.deviation_ns) > self.window_ns

    def measure(self, dt_us: int, rng: random.Random) -> None:
        """The deviation of the master clock from the reference clock after ``dt_us``."""
        if self.state is DcState.IDLE:
            self.deviation_ns = 0
            return
        if self.fault == "drift":
            self.deviation_ns += DRIFT_NS_PER_MS * max(1, dt_us // 1000)
        elif self.fault == "jitter":
            spread = JITTER_FACTOR * self.window_ns
            self.deviation_ns = draw(rng, -spread, 2 * spread + 1)
        else:
            self.deviation_ns = draw(rng, -NOISE_NS, NOISE_SPAN)

    def compensate(self, rng: random.Random) -> bool:
        """A COMPENSATING cycle without a fault, link up and DC slaves present, made short:
        :meth:`measure` (the healthy noise) and, when the deviation is in the window, all
        :meth:`trigger` would do (``outside`` back to 0, no trigger); True then. False: the
        deviation is out of the window (a window under NOISE_NS), ``trigger`` must count it."""
        self.deviation_ns = dev = rng._randbelow(NOISE_SPAN) - NOISE_NS  # draw(), inlined
        if -self.window_ns <= dev <= self.window_ns:
            self.outside = 0
            return True
        return False

    def trigger(self, now_us: int, link: bool, dc_slaves: int,
                dc_slaves_ready: bool) -> DcTrigger | None:
        """The trigger that applies now, or None (checked against the table by the caller)."""
        state, waited = self.state, now_us - self.since_us
        if not link or dc_slaves == 0:
            return DcTrigger.LINK_DOWN if state is not DcState.IDLE else None
        if state is DcState.IDLE:
            return DcTrigger.LINK_UP
        if state is DcState.NOT_SYNCHRONIZED:
            gone = self.fault is None and waited >= RESYNC_AFTER_US
            return DcTrigger.FAULT_GONE if gone else None
        out = self.out_of_window()
        self.outside = self.outside + 1 if out else 0
        if state is DcState.SYNCHRONIZING:
            # Seed 003: WAITING_START_TIME comes "after the master has synced with the slaves":
            # the measurements end synced (steadily inside the window) or failed (steadily
            # outside it); anything between measures on.
            self.inside = 0 if out else self.inside + 1
            if waited < SYNC_MEASURE_US:
                return None
            if self.inside >= LOCK_CYCLES:
                return DcTrigger.MEASURED
            return DcTrigger.OUT_OF_WINDOW if self.outside >= OUT_OF_WINDOW_CYCLES else None
        if self.outside >= OUT_OF_WINDOW_CYCLES:
            return DcTrigger.OUT_OF_WINDOW
        if state is DcState.WAITING_START_TIME:
            if not dc_slaves_ready:
                self.start_time_us = None
                return None
            if self.start_time_us is None:
                self.start_time_us = now_us + START_DELAY_US
            return DcTrigger.START_TIME if now_us >= self.start_time_us else None
        return None

    def move(self, trigger: DcTrigger, now_us: int) -> tuple[DcState, DcState] | None:
        """Apply ``trigger``: (from, to) when the table has the transition, else None."""
        target = DC_TRANSITIONS.get((self.state, trigger))
        if target is None:
            return None
        before, self.state, self.since_us = self.state, target, now_us
        if target in (DcState.SYNCHRONIZING, DcState.IDLE):
            self.deviation_ns, self.start_time_us, self.outside, self.inside = 0, None, 0, 0
        return before, target

    def measured(self) -> bool:
        """Whether the master measures a deviation: not in IDLE, where its clock is
        "completely independent from the slaves" (seed 003)."""
        return self.state is not DcState.IDLE

    def snapshot(self) -> dict[str, object]:
        """What the master's DC management shows: its state, the deviation it measured (None
        in IDLE: nothing is measured, and 0 would read as in sync) and the window; the
        injected fault is the simulator's (the master's ``injected``)."""
        return {"state": self.state.value,
                "deviation_ns": self.deviation_ns if self.measured() else None,
                "window_ns": self.window_ns}
