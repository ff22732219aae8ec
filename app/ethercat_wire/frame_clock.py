"""The pace of the frames the bridge (app/ethercat_wire/bridge.py) hands each slave's model:
process B reports frame counts in bursts, the models get them one master cycle apart."""

from __future__ import annotations

from dataclasses import dataclass

from app.ethercat_wire import messages as msg

PERIOD_SMOOTHING = 0.3  # weight of the newest report in the cycle estimate
CYCLE_TOLERANCE = 0.25  # B's cycle measurements within this of each other agree
ALIVE_REPORTS = 3  # the master counts as cycling this many report intervals after a report
MAX_OWED_REPORTS = 2  # frames owed beyond this many reports' worth are forgotten
MAX_FRAMES_PER_STEP = 16


@dataclass
class FrameClock:
    """When to hand one slave's model a process-data frame.

    B reports how many frames a slave saw since its last report (every 10 ms of wall time).
    Handing them over in bursts would leave cycles without a frame: the TRS-CAT runs SYNC0 on
    the cycle the master wrote to 0x09A0 (``("dc", ...)`` -> ``configure_dc``) and counts
    SYNC0 cycles without a frame as sync errors (seed 001 §9.1.1, §9.3.7). So the frames go
    out one master cycle apart: the cycle is the reported rate in wall time (smoothed; a
    simulated microsecond is a wall microsecond at speed 1, and a clock that falls behind
    under load must not make the master look faster), for as long as reports keep saying
    that the master cycles. The count owed keeps the total close to what B saw; frames the
    simulation cannot keep up with are forgotten rather than handed over in a burst.
    """

    period_us: float = 0.0
    next_us: float = 0.0
    owed: int = 0
    alive_until: float = 0.0  # monotonic wall time
    measured: bool = False  # period_us is B's own measurement (``master_cycle``)
    candidate: float = 0.0  # a measurement far from period_us, adopted if the next agrees

    def report(self, n: int, span_s: float, now_us: int, wall: float) -> None:
        if n <= 0:
            return
        if not self.measured:  # a rough estimate until B's first measurement comes
            sample = span_s * 1e6 / n
            self.period_us = sample if not self.period_us else \
                (1 - PERIOD_SMOOTHING) * self.period_us + PERIOD_SMOOTHING * sample
        self.owed = min(self.owed + n, MAX_OWED_REPORTS * n)
        self.alive_until = wall + ALIVE_REPORTS * msg.CYCLE_REPORT_S
        if self.next_us < now_us - self.period_us:
            self.next_us = now_us  # the master (re)starts: no catching up on the pause

    def restart(self) -> None:
        """The simulated clock went back (a scenario load): the next frame at once, none owed
        from the old run; B's cycle measurement stays (the wire master did not change)."""
        self.next_us, self.owed = 0.0, 0

    def master_cycle(self, cycle_us: float) -> None:
        """B's mean process-data period over its last stats interval, on B's own clock. The
        estimate from the reports is only as good as A's timing of them: a starved pump or a
        busy simulation thread takes several at once (spans near 0), and B merges the counts
        of reports A could not take: that made the period look like 1 ms at a 4 ms cycle.
        A mean over a window in which the master started or paused is too long: a value far
        from the present one (and the first one: the window the master started in, 25 ms seen
        at a 4 ms cycle) is taken only when the very next measurement agrees with it (two
        windows cut by a pause, e.g. around config_map, would otherwise agree on 20 ms).
        """
        if cycle_us <= 0:
            self.candidate = 0.0  # no frames: the next measurement is not "the next" one
            return
        if (self.measured and _close(cycle_us, self.period_us)) or \
                _close(cycle_us, self.candidate):
            self.period_us, self.measured, self.candidate = float(cycle_us), True, 0.0
        else:
            self.candidate = float(cycle_us)

    def due(self, now_us: int, wall: float) -> int:
        """Frames to hand over at ``now_us``."""
        if not self.period_us or (self.owed <= 0 and wall > self.alive_until):
            return 0
        count = 0
        while self.next_us <= now_us and count < MAX_FRAMES_PER_STEP:
            count += 1
            self.next_us += self.period_us
            self.owed = max(0, self.owed - 1)
        if self.next_us <= now_us:
            self.next_us = now_us + self.period_us
        return count


def _close(a: float, b: float) -> bool:
    return b > 0 and abs(a - b) <= CYCLE_TOLERANCE * b

