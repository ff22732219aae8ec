"""Issue 7 benchmark 3 "send only what changed", panel by panel: the master panel's summary and
the drive plots' x range, counted on the messages a real viser server queues (its send path
patched to record), frame after frame of a rig standing idle.

- the master panel (app/ui/line/master_panel.py): the time in the title moves ten times a
  second, the frame counter and the DC deviation (drawn each cycle) every frame; phase, target,
  link, the slave table and the log stand. Each stands in its own handle, rewritten only when
  its own text changes (it was one block rewritten every frame: ~29 messages/s, 15 kB/s);
- the drive plots (app/ui/drive/plots.py): viser sends a property each time it is assigned,
  equal or not; the uPlot ``scales`` go out only when the x range moves (it stands at
  0..WINDOW_S until the window fills, then slides), the data with every new sample, but only
  the samples that shape the line (a still drive: a few points a chart, not 1000 float64 t and
  value pairs, 48 kB a write for the three).
"""

from __future__ import annotations

import collections
from collections.abc import Iterator
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import viser

from app.screenshots import free_port
from app.ui.drive.plots import (
    SAMPLE_US,
    SIGNALS,
    WINDOW_S,
    DrivePlots,
    DriveSampler,
    line_points,
)
from app.ui.line.master_panel import MasterPanel

FRAME_US = 33_000  # one dashboard frame of simulated time (the runtime publishes at 30 Hz)
FRAMES = 90  # three seconds


@dataclass
class Recorder:
    """(GUI id, property) -> the values queued for the browsers, in order."""

    sent: dict[tuple[str, str], list[Any]] = field(
        default_factory=lambda: collections.defaultdict(list))

    def record(self, message: Any) -> None:
        if type(message).__name__ == "GuiUpdateMessage":
            for prop, value in message.updates.items():
                self.sent[(message.uuid, prop)].append(value)

    def clear(self) -> None:
        self.sent.clear()


@pytest.fixture
def server() -> Iterator[tuple[viser.ViserServer, Recorder]]:
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    recorder = Recorder()
    queue = server._websock_server.queue_message

    def recorded(message: Any) -> None:
        recorder.record(message)
        queue(message)
    server._websock_server.queue_message = recorded  # type: ignore[method-assign]
    try:
        yield server, recorder
    finally:
        server.stop()


# ---- the master panel --------------------------------------------------------------------------
def master(frame: int, **changes: Any) -> dict[str, Any]:
    """The built-in master's snapshot in OP, ``frame`` dashboard frames in: what moves from one
    frame to the next is the frame counter (a frame a 1 ms cycle) and the DC deviation."""
    slave = {"position": 0, "station_address": 1001, "name": "Box 1 (FastCAT)", "state": "OP",
             "requested": "OP", "al_status": 8, "al_status_code": 0, "dc": False, "link": True,
             "counters": {"lost_frames": 0, "wkc_errors": 0, "emergencies": 0,
                          "state_changes": 3},
             "esc_errors": {"invalid": [0, 0], "rx": [0, 0], "forwarded": [0, 0],
                            "lost_link": [0, 0], "epu": 0}}
    snap = {"id": "master", "phase": "running", "target": "OP", "link": True,
            "dc": {"state": "COMPENSATING", "fault": None, "deviation_ns": (frame * 37) % 41 - 20,
                   "window_ns": 1000},
            "stats": {"frames": 8000 + frame * 33, "lost_frames": 0, "cycle_us": 1000},
            "slaves": [slave], "log": [{"timestamp": "12/11/2019 14.51.30 451 ms",
                                        "text": "distributed clocks: COMPENSATING"}],
            "log_style": "twincat"}
    return {**snap, **changes}


def shown_by(recorder: Recorder) -> dict[str, str]:
    """GUI id -> what its first content says (``status``, ``live``, ...), from the writes."""
    markers = {'<b>EtherCAT master</b>': "title", 'id="fr-line-master-status"': "status",
               'id="fr-line-master"': "live", 'id="fr-line-slaves"': "slaves",
               'id="fr-line-log"': "log", 'id="fr-line-esc-errors"': "esc_errors"}
    names = {}
    for (uuid, prop), values in recorder.sent.items():
        if prop == "content":
            found = [name for marker, name in markers.items() if marker in values[0]]
            assert len(found) == 1, f"one block holds {found}: {values[0]}"
            names[uuid] = found[0]
    return names


@dataclass
class Idle:
    panel: MasterPanel
    recorder: Recorder
    names: dict[str, str]  # GUI id -> block
    counts: collections.Counter[str]  # block -> content writes in the idle frames
    t_end: int  # the last frame's simulated time


def idle_master(server: Any) -> Idle:
    """FRAMES idle frames after the first: content writes per block, and the t of the last."""
    viser_server, recorder = server
    panel = MasterPanel(viser_server, SimpleNamespace(), "master")  # type: ignore[arg-type]
    t0 = 8_000_000
    panel.update(master(0), t0)
    names = shown_by(recorder)
    assert sorted(names.values()) == ["esc_errors", "live", "log", "slaves", "status",
                                      "title"]
    recorder.clear()
    for n in range(1, FRAMES + 1):
        panel.update(master(n), t0 + n * FRAME_US)
    counts = collections.Counter({name: 0 for name in names.values()})
    for (uuid, prop), values in recorder.sent.items():
        if prop == "content":
            counts[names[uuid]] += len(values)
    return Idle(panel, recorder, names, counts, t0 + FRAMES * FRAME_US)


def test_idle_master_sends_only_its_moving_values(server: Any) -> None:
    """Phase, target, link, the slave table, the ESC error counters and the log: not resent
    while only the time, the frame counter and the DC deviation move. The time: once a tenth
    of a second it shows."""
    idle = idle_master(server)
    counts = idle.counts
    assert counts["status"] == counts["slaves"] == counts["log"] == counts["esc_errors"] == 0
    tenths = round(idle.t_end / 100_000) - round(8_000_000 / 100_000)
    assert tenths - 1 <= counts["title"] <= tenths + 1
    assert counts["live"] == FRAMES  # the counter moved every frame: written every frame


def test_idle_master_live_block_is_small(server: Any) -> None:
    """What goes out every frame is the DC and Frames rows, not the summary with them."""
    sent = idle_master(server).recorder.sent
    live = [v for (_, prop), values in sent.items() if prop == "content"
            for v in values if 'id="fr-line-master"' in v]
    assert live and all(v.count("<tr>") == 2 and "Phase" not in v for v in live)
    assert max(len(v) for v in live) < 300


@pytest.mark.parametrize(("change", "blocks"), [
    ({"phase": "safe_op"}, ["status"]),
    ({"target": "SAFEOP"}, ["status", "slaves"]),  # a slave in OP is no longer at target
    ({"link": False}, ["status"]), ({"external": True}, ["status"]),
    ({"dc": {"state": "NOT_SYNCHRONIZED", "fault": "drift", "deviation_ns": 74998,
             "window_ns": 1000}}, ["live"]),
])
def test_master_block_follows_its_values(server: Any, change: dict[str, Any],
                                         blocks: list[str]) -> None:
    """A change of phase, target or link rewrites the status table once; the DC state its row."""
    idle = idle_master(server)
    idle.recorder.clear()
    snap = master(FRAMES, **change)
    for _ in range(3):  # the same frame shown three times: the change goes out once
        idle.panel.update(snap, idle.t_end)
    written = {idle.names[uuid]: values for (uuid, prop), values
               in idle.recorder.sent.items() if prop == "content"}
    assert sorted(written) == sorted(blocks)
    assert all(written[block] == [idle.panel.text(block)] for block in blocks)


# ---- the drive plots ---------------------------------------------------------------------------
STILL = {"position_counts": 1.0, "velocity": 0.0, "following_error": 0.0}


def plots(server: Any, snapshot: Any = lambda: STILL
          ) -> tuple[DrivePlots, DriveSampler, Recorder]:
    viser_server, recorder = server
    sampler = DriveSampler(snapshot)
    chart_plots = DrivePlots(viser_server, sampler)
    recorder.clear()
    return chart_plots, sampler, recorder


def run(chart_plots: DrivePlots, sampler: DriveSampler, start_us: int, end_us: int,
        every_us: int) -> None:
    """Samples from start_us to end_us; the charts written every ``every_us``."""
    for now_us in range(start_us, end_us + 1, SAMPLE_US):
        sampler.on_step(now_us)
        if now_us % every_us == 0:
            assert chart_plots.update(now_us / 1e6, now_us, force=True)


def per_chart(recorder: Recorder, prop: str) -> list[list[Any]]:
    return [values for (_, p), values in recorder.sent.items() if p == prop]


def test_plot_range_sent_once_while_the_window_fills(server: Any) -> None:
    """0..20 s stands until 20 s of samples are in: one ``scales`` per chart, data each time."""
    chart_plots, sampler, recorder = plots(server)
    run(chart_plots, sampler, 0, 10_000_000, 1_000_000)
    scales, data = per_chart(recorder, "scales"), per_chart(recorder, "data")
    assert len(scales) == len(data) == 3
    assert all(len(values) == 11 for values in data)
    assert all(values == [{"x": {"time": False, "auto": False, "range": (0.0, WINDOW_S)}}]
               for values in scales)


def test_plot_range_follows_the_sliding_window(server: Any) -> None:
    """Past 20 s the range moves with each write: sent each time, with the new range."""
    chart_plots, sampler, recorder = plots(server)
    run(chart_plots, sampler, 0, 24_000_000, 1_000_000)
    scales, data = per_chart(recorder, "scales"), per_chart(recorder, "data")
    # 0..20 s: one range; 21, 22, 23, 24 s: one each.
    assert [len(values) for values in scales] == [5, 5, 5] and len(data[0]) == 25
    assert scales[0][-1]["x"]["range"] == (24.0 - WINDOW_S, 24.0)
    recorder.clear()
    chart_plots.update(25.0, 24_000_000, force=True)  # nothing new sampled: nothing sent
    assert recorder.sent == {}


@pytest.mark.parametrize(("values", "kept"), [
    ([], []), ([5.0], [0]), ([5.0, 5.0], [0, 1]), ([3.0] * 6, [0, 5]),
    ([0.0, 0.0, 0.0, 7.0, 7.0, 7.0], [0, 2, 3, 5]),  # a step: both sides of it
    ([0.0, 1.0, 2.0, 3.0], [0, 1, 2, 3]),  # a ramp without times: every sample
    ([1.0, 1.0, float("nan"), 1.0, 1.0], [0, 1, 2, 3, 4]),
])
def test_line_points(values: list[float], kept: list[int]) -> None:
    assert line_points(np.asarray(values, dtype=np.float64)).tolist() == kept


@pytest.mark.parametrize("seed", range(5))
def test_line_points_draw_the_same_line(seed: int) -> None:
    """Through the kept samples, the line passes by every sample left out (runs of equal
    values with steps and ramps between them, as a drive that moves, stops, moves)."""
    rng = np.random.default_rng(seed)
    values = np.repeat(rng.integers(-3, 4, 40).astype(np.float64), rng.integers(1, 30, 40))
    t = np.arange(len(values)) * SAMPLE_US / 1e6
    shape = line_points(values)
    assert len(shape) < len(values)
    assert np.array_equal(np.interp(t, t[shape], values[shape]), values)


def test_still_drive_plots_a_few_points(server: Any) -> None:
    """A drive standing still for 24 s: two points a chart, the ends of its flat line; the
    charts still say how many samples their lines go through."""
    chart_plots, sampler, recorder = plots(server)
    run(chart_plots, sampler, 0, 24_000_000, 1_000_000)
    last = [values[-1] for values in per_chart(recorder, "data")]
    assert [t.tolist() for t, _ in last] == [[24.0 - WINDOW_S, 24.0]] * len(SIGNALS)
    assert [v.tolist() for _, v in last] == [[STILL[key]] * 2 for key, _, _ in SIGNALS]
    assert chart_plots.drawn_points() == int(WINDOW_S * 1e6 / SAMPLE_US) + 1


def test_moving_drive_plots_the_ends_of_its_ramp(server: Any) -> None:
    """Position ramping at constant velocity: the two ends of the ramp (a straight line), the
    two ends of the velocity's plateau; the charts still say how many samples they cover."""
    clock = {"t": 0.0}
    chart_plots, sampler, recorder = plots(server, lambda: {
        "position_counts": 1000.0 * clock["t"], "velocity": 1000.0, "following_error": 0.0})
    for now_us in range(0, 5_000_001, SAMPLE_US):
        clock["t"] = now_us / 1e6
        sampler.on_step(now_us)
    assert chart_plots.update(5.0, 5_000_000, force=True)
    position, velocity, _ = (values[-1] for values in per_chart(recorder, "data"))
    assert position[0].tolist() == [0.0, 5.0] and position[1].tolist() == [0.0, 5000.0]
    assert velocity[0].tolist() == [0.0, 5.0] and velocity[1].tolist() == [1000.0, 1000.0]
    assert chart_plots.drawn_points() == 251


@pytest.mark.parametrize("seed", range(5))
def test_line_points_with_times_draw_the_same_line(seed: int) -> None:
    """Ramps, plateaus and bends of a drive that accelerates, cruises, stops (sample times as
    the sampler takes them, not exact in binary): the kept samples draw every sample left
    out to within float rounding, and every bend is kept."""
    rng = np.random.default_rng(seed)
    slopes = np.repeat(rng.integers(-3, 4, 30) * 1000.0, rng.integers(1, 40, 30))
    t = np.arange(len(slopes) + 1) * SAMPLE_US / 1e6
    values = np.concatenate(([0.0], np.cumsum(slopes * SAMPLE_US / 1e6)))
    shape = line_points(values, t)
    assert len(shape) < len(values) / 2
    drawn = np.interp(t, t[shape], values[shape])
    assert np.allclose(drawn, values, rtol=0, atol=1e-6 * np.ptp(values))
    bends = np.flatnonzero(slopes[1:] != slopes[:-1]) + 1  # where the slope changes
    assert set(bends.tolist()) <= set(shape.tolist())
