"""Live plots of the drive: position, velocity and following error over simulated time.

Samples are taken in the simulation thread, every :data:`SAMPLE_US` of *simulated* time (a
runtime step listener reading the drive's snapshot), not from the frames the view receives:
a paused rig advanced by 20 s in one go still gets a full curve, and a screenshot at a given
simulated instant always shows the same plot. The dashboard thread sends the last
:data:`WINDOW_S` seconds to the uPlot charts a few times a second.

viser sends a chart's whole data with each write, as raw float64 (uncompressed): 1000 samples
of t and value for three charts are 48 kB a write, ~180 kB/s to each browser for a drive that
stands still (benchmark 3, docs/performance.md). A chart gets only the samples that shape its
line, :func:`line_points`: a run of equal values, or a straight run (a position ramping at
constant velocity), is drawn by its first and last sample alone (the line between them is the
same), so a still drive costs a few points a chart and a jogging one a few more.
"""

from __future__ import annotations

import collections
import threading
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import viser

from app.rig import FAR_US

SAMPLE_US = 20_000  # 50 samples per simulated second
WINDOW_S = 20.0  # the plots show the last 20 simulated seconds
SEND_PERIOD_S = 0.25  # wall time between two updates of the charts
PLOT_HEIGHT = 64  # pixels of one chart without its time axis
TIME_AXIS_HEIGHT = 28
VALUE_AXIS_WIDTH = 70  # room for "-600,000"
STRAIGHT = 1e-9  # a turn this small against the segments' size is float rounding, not a bend

# (snapshot key, title, colour)
SIGNALS: tuple[tuple[str, str, str], ...] = (
    ("position_counts", "Position (user units)", "#1f4f8f"),
    ("velocity", "Velocity (user units / s)", "#1d8b4a"),
    ("following_error", "Following error (user units)", "#c0392b"),
)

SnapshotFn = Callable[[], Mapping[str, Any] | None]
LoadCount = Callable[[], int]  # the rig's scenario loads (Rig.loads)


def line_points(values: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
    """The indices of the samples that shape a line through ``values``: the first, the last,
    and each one where the line turns. Left out: the inside of a run of equal values and, given
    the times ``t``, the inside of a straight run (a position ramping at constant velocity),
    which lie on the segment between the run's ends."""
    keep = np.ones(len(values), dtype=bool)
    if len(values) <= 2:
        return np.flatnonzero(keep)
    if t is None:
        moved = values[1:] != values[:-1]  # NaN != NaN: a NaN is kept
        keep[1:-1] = moved[:-1] | moved[1:]
        return np.flatnonzero(keep)
    dv, dt = np.diff(values), np.diff(t)
    # The turn at a sample: the cross product of the segments either side, against their
    # size. STRAIGHT leaves out only what float rounding bends (sample times are not exact in
    # binary); a NaN compares False and is kept.
    turn = np.abs(dv[:-1] * dt[1:] - dv[1:] * dt[:-1])
    size = (np.abs(dv[:-1]) + np.abs(dv[1:])) * (dt[:-1] + dt[1:])
    keep[1:-1] = ~(turn <= STRAIGHT * size)
    return np.flatnonzero(keep)


class DriveSampler:
    """A ring of (t, position, velocity, following error), filled in the simulation thread."""

    def __init__(self, snapshot: SnapshotFn, window_s: float = WINDOW_S,
                 loads: LoadCount = lambda: 0) -> None:
        self._snapshot = snapshot
        self._loads = loads
        self._load = loads()  # the load the samples are of
        self._lock = threading.Lock()
        self._rows: collections.deque[tuple[float, ...]] = collections.deque(
            maxlen=int(window_s * 1e6 / SAMPLE_US) + 1)
        self._next_us: int | None = None
        self.version = 0  # bumps with every sample: the view sends only when it moved
        self.active = True

    def on_step(self, now_us: int) -> None:
        """Runtime step listener (simulation thread): one sample every SAMPLE_US."""
        if not self.active:
            return
        self.new_run()
        with self._lock:  # new_run may reset the timeline from the view's thread
            if self._next_us is None:  # samples on multiples of SAMPLE_US: the same every run
                self._next_us = -(-now_us // SAMPLE_US) * SAMPLE_US
            if now_us < self._next_us:
                return
            self._next_us = now_us - now_us % SAMPLE_US + SAMPLE_US
        snap = self._snapshot()
        if not snap:
            return
        row = (now_us / 1e6, *(float(snap.get(key, 0.0) or 0.0) for key, _, _ in SIGNALS))
        with self._lock:
            self._rows.append(row)
            self.version += 1

    def quiet_until(self, now_us: int, step_us: int) -> int:
        """Up to when :meth:`on_step` would take no sample (Runtime.add_step_listener): the
        step before the next sample time; none while the timeline is not set."""
        if not self.active:
            return FAR_US
        due = self._next_us
        if due is None or self._loads() != self._load:
            return now_us  # the next step sets the timeline (or starts a fresh one)
        return due - 1

    def new_run(self) -> bool:
        """Start afresh if a scenario was loaded since the samples began (either thread: the
        simulation's next step or the view at the load, whichever comes first). The load, not
        the clock going back: a load at 0 s, or right after another, puts no clock back, and
        a paused rig takes no step to see it by."""
        load = self._loads()
        with self._lock:
            if load == self._load:
                return False
            self._load, self._next_us = load, None
            self._rows.clear()
            self.version += 1
        return True

    def reset(self) -> None:
        """Forget the samples (another drive was selected); called from the view."""
        with self._lock:
            self._rows.clear()
            self.version += 1

    def columns(self) -> tuple[np.ndarray, ...]:
        """(t, position, velocity, following error) as arrays, oldest first."""
        with self._lock:
            rows = list(self._rows)
        if not rows:
            return tuple(np.zeros(0) for _ in range(len(SIGNALS) + 1))
        data = np.asarray(rows, dtype=np.float64)
        return tuple(data[:, i] for i in range(data.shape[1]))


class DrivePlots:
    """Three small uPlot charts sharing the time axis (simulated seconds)."""

    def __init__(self, server: viser.ViserServer, sampler: DriveSampler,
                 visible: bool = True) -> None:
        """``visible``: shown on a new page (each drive's charts, the picked drive's shown)."""
        self._sampler = sampler
        self._sent_version = -1
        self._sent_at = 0.0
        # viser sends a property each time it is assigned, equal or not: the x range is set
        # only when it moves (it stands at 0..WINDOW_S until the window fills, then slides).
        self._sent_range: tuple[float, float] | None = None
        self._sent_samples = 0
        empty = (np.zeros(1), np.zeros(1))
        last = len(SIGNALS) - 1
        # One time axis for the three, under the last chart: the others are shorter by it.
        self._charts = [
            server.gui.add_uplot(
                empty, ({"label": "t (s)"},
                        # No point markers: uPlot shows them where points are sparse, as a run
                        # reduced to its ends is (samples 20 ms apart on a 20 s axis never are,
                        # so the page showed none before either).
                        {"label": label.split(" (")[0], "stroke": colour, "width": 1.5,
                         "points": {"show": False}}),
                title=label, height=PLOT_HEIGHT + (TIME_AXIS_HEIGHT if i == last else 0),
                legend={"show": False}, cursor={"show": False},
                scales={"x": {"time": False}},
                axes=({"show": i == last, "size": TIME_AXIS_HEIGHT}, {"size": VALUE_AXIS_WIDTH}),
                padding=(8, 12, 6, 0), visible=visible)
            for i, (_key, label, colour) in enumerate(SIGNALS)]

    @property
    def charts(self) -> list[Any]:
        return list(self._charts)

    def update(self, now: float, t_us: int, force: bool = False) -> bool:
        """Send new samples when there are some and the last send is SEND_PERIOD_S old
        (``now`` is wall time); True when the charts were written."""
        version = self._sampler.version
        if version == self._sent_version:
            return False
        if not force and now - self._sent_at < SEND_PERIOD_S:
            return False
        columns = self._sampler.columns()
        if len(columns[0]) == 0:  # a new run (or drive) without a sample yet: blank charts
            for chart in self._charts:
                chart.data = (np.zeros(1), np.zeros(1))
            self._sent_range, self._sent_samples = None, 0
            self._sent_version, self._sent_at = version, now
            return True
        t_end = max(float(columns[0][-1]), t_us / 1e6)
        x_range = (max(0.0, t_end - WINDOW_S), max(t_end, WINDOW_S))
        scales = None if x_range == self._sent_range else {
            "x": {"time": False, "auto": False, "range": x_range}}
        for chart, values in zip(self._charts, columns[1:], strict=True):
            if scales is not None:
                chart.scales = scales
            shape = line_points(values, columns[0])
            chart.data = (columns[0][shape], values[shape])
        self._sent_range, self._sent_samples = x_range, len(columns[0])
        self._sent_version, self._sent_at = version, now
        return True

    def caught_up(self) -> bool:
        """True when the charts hold every sample taken so far (tests)."""
        return self._sent_version == self._sampler.version

    def drawn_points(self) -> int:
        """Samples the charts' lines go through now (tests)."""
        return self._sent_samples
