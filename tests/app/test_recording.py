"""Rerun recordings of a rig (issue 6, "Recording (rerun-sdk)").

Acceptance: a recording that ``rerun rrd verify`` accepts and that holds the expected entities.
The recordings are read back with the SDK's own RRD reader (``rerun.chunk.RrdReader``), so the
tests check what a viewer would load, not what the recorder meant to write. No viewer is ever
spawned.
"""

from __future__ import annotations

import datetime as dt
import math
import subprocess
import sys
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from rerun.chunk import RrdReader

from app.recording import RigRecorder, attach_to_runtime, event_text, scenario_observer
from app.recording.signals import rig_signals
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from devices.events import (
    AlarmChanged,
    AlStatusChanged,
    Caption,
    Checkpoint,
    EmergencySent,
    Event,
    LedChanged,
    LogLine,
    StateChanged,
    ValueRead,
)
from devices.leds import LedPattern, is_lit

RERUN = [sys.executable, "-m", "rerun"]
S = 1_000_000
FLUSH_US = 1_000_000


def rerun_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*RERUN, *args], capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module", autouse=True)
def _no_analytics() -> None:
    """The CLI asks about analytics on its first run; a test machine says no up front."""
    rerun_cli("analytics", "disable")


# ---- reading a recording back ------------------------------------------------------------------
Chunks = dict[str, list[Any]]  # entity path (no leading "/") -> its chunks as record batches


def load(path: Path) -> Chunks:
    reader = RrdReader(str(path))
    out: Chunks = defaultdict(list)
    for chunk in reader.stream(store=reader.recordings()[0]):
        out[chunk.entity_path.lstrip("/")].append(chunk.to_record_batch())
    return out


def rows(chunks: Chunks, path: str, component: str) -> list[tuple[int, Any]]:
    """(sim time in us, value) of every row of ``component`` under ``path``, in time order.
    A single-instance value is unwrapped; a multi-series scalar row stays a list."""
    out: list[tuple[int, Any]] = []
    for batch in chunks.get(path, []):
        names = batch.schema.names
        if component not in names or "sim_time" not in names:
            continue
        for t, value in zip(batch.column("sim_time").to_pylist(),
                            batch.column(component).to_pylist(), strict=True):
            out.append((t // dt.timedelta(microseconds=1),
                        value[0] if len(value) == 1 else value))
    return sorted(out, key=lambda r: r[0])


def value_at(lane: list[tuple[int, Any]], t_us: int) -> Any:
    """The value a state lane shows at ``t_us`` (its last change at or before it)."""
    current = None
    for t, value in lane:
        if t > t_us:
            break
        current = value
    return current


# ---- one recorded run of the default rig ---------------------------------------------------------
class Run:
    """The default rig driven through a short story, recorded per simulation step."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.rig: Rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
        self.recorder = RigRecorder(path, recording_id="test-run", flush_period_us=FLUSH_US)
        self.hook = scenario_observer(self.recorder)
        self.events: list[Event] = []

    def do(self, target: str, action: str, **args: Any) -> None:
        self.rig.apply(target, action, args)
        self._seen(self.rig.take_events())

    def run_until(self, t_us: int) -> None:
        while self.rig.clock.now_us + self.rig.clock.step_us <= t_us:
            self._seen(self.rig.step())

    def _seen(self, events: list[Event]) -> None:
        self.events.extend(events)
        self.hook(self.rig, events)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "run.rrd")
    r.do("fastcat", "power", on=True)
    r.run_until(int(3.5 * S))  # the master brings the coupler to OP (seed 000 §7)
    r.do("fastcat/1", "set_input", channel=3, value=True)
    r.do("fastcat/7", "set_shaft_speed", encoder=1, rpm=600.0)
    r.run_until(4 * S)
    r.do("fastcat/2", "unplug")  # module lost in OP: alarm, emergency, back to PREOP
    r.run_until(6 * S)
    r.recorder.close()
    return r


@pytest.fixture(scope="module")
def chunks(run: Run) -> Chunks:
    return load(run.path)


def test_rrd_verify_accepts_the_recording(run: Run) -> None:
    result = rerun_cli("rrd", "verify", str(run.path))
    assert result.returncode == 0, result.stderr
    assert "verified without error" in result.stderr


EXPECTED = [
    ("rig/fastcat/events", "TextLog:text"),
    ("rig/master/events", "TextLog:text"),
    ("rig/fastcat/state", "StateChange:state"),
    ("rig/fastcat/led/RUN", "Scalars:scalars"),
    ("rig/fastcat/led/RUN", "StateChange:state"),
    ("rig/fastcat/led/ERR", "Scalars:scalars"),
    ("rig/fastcat/led/LINK", "StateChange:state"),
    ("rig/fastcat/led/2.yellow", "StateChange:state"),
    ("rig/fastcat/io/1/di", "Scalars:scalars"),
    ("rig/fastcat/io/1/do", "Scalars:scalars"),
    ("rig/fastcat/io/2/di", "Scalars:scalars"),
    ("rig/fastcat/io/3/do", "Scalars:scalars"),
    ("rig/fastcat/io/4/ai", "Scalars:scalars"),
    ("rig/fastcat/io/5/ao", "Scalars:scalars"),
    ("rig/fastcat/io/6/ai", "Scalars:scalars"),
    ("rig/fastcat/io/7/position", "Scalars:scalars"),
    ("rig/fastcat/io/7/rpm", "Scalars:scalars"),
]


@pytest.mark.parametrize(("path", "component"), EXPECTED)
def test_recording_holds_expected_entities(chunks: Chunks, path: str, component: str) -> None:
    assert rows(chunks, path, component), f"no {component} rows under {path}"


def test_rrd_stats_lists_the_entities(run: Run) -> None:
    result = rerun_cli("rrd", "stats", str(run.path))
    assert result.returncode == 0, result.stderr
    for path in {p for p, _ in EXPECTED}:
        assert f"/{path}:" in result.stdout


def test_data_is_on_the_simulated_timeline_only(chunks: Chunks) -> None:
    """No wall-clock time line: a recording of a run is the same however fast it ran."""
    for path, batches in chunks.items():
        if not path.startswith("rig/"):
            continue
        for batch in batches:
            assert not {"log_time", "log_tick"} & set(batch.schema.names), path


def test_esm_lane_follows_the_state_events(run: Run, chunks: Chunks) -> None:
    changes = [(e.t_us, e.to_state) for e in run.events
               if isinstance(e, StateChanged) and e.device == "fastcat" and not e.machine]
    assert [s for _, s in changes][:3] == ["PREOP", "SAFEOP", "OP"]
    assert rows(chunks, "rig/fastcat/state", "StateChange:state") == [(0, "INIT"), *changes]


def test_every_event_is_one_text_line_at_its_time(run: Run, chunks: Chunks) -> None:
    for device in ("fastcat", "master"):
        mine = [e for e in run.events if e.device == device]
        logged = rows(chunks, f"rig/{device}/events", "TextLog:text")
        assert [t for t, _ in logged] == [e.t_us for e in mine]
        assert [text for _, text in logged] == [
            event_text.text(e, e.to_record(), run.recorder.al_status) for e in mine]


def test_emergency_and_alarm_are_warnings_and_errors(run: Run, chunks: Chunks) -> None:
    """Unplugging module 2 in OP: alarm 0x04 and EMCY FF00 with module 2 in byte 0 (seed 000
    §7); the recording shows them at a higher level than the rest."""
    texts = rows(chunks, "rig/fastcat/events", "TextLog:text")
    levels = rows(chunks, "rig/fastcat/events", "TextLog:level")
    by_text = {text: level for (_, text), (_, level) in zip(texts, levels, strict=True)}
    emcy = next(e for e in run.events if isinstance(e, EmergencySent))
    alarm = next(e for e in run.events if isinstance(e, AlarmChanged) and e.active)
    assert by_text[event_text.text(emcy, emcy.to_record())] == "WARN"
    assert by_text[event_text.text(alarm, alarm.to_record())] == "ERROR"
    assert by_text["state: OP -> PREOP"] == "INFO"


def test_the_fastcat_al_status_code_is_read_as_the_coupler_reads_it(chunks: Chunks) -> None:
    """Seed 000 §7.7: 0x80XX carries the module (byte 1) and the coupler code (byte 0); the
    State and Codes tabs and the master's log read it so. The recording said "Manufacturer
    specific" for every one of them."""
    texts = [t for _, t in rows(chunks, "rig/fastcat/events", "TextLog:text")
             if t.startswith("AL status code 0x8")]
    assert texts == ["AL status code 0x8204: module 2: coupler code 0x04 MISSING_NODE_ANSWER"]


def test_al_status_reader_falls_back_to_the_etg_text() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    read = event_text.al_status_reader(rig.devices)
    assert read("fastcat", 0x8001) == "coupler: coupler code 0x01 MODULE_CHANGED"
    assert read("trscat", 0x8204) == "Manufacturer specific"  # no codes of its own
    assert read("gone", 0x001B) == "Sync manager watchdog"


@pytest.mark.parametrize("led", ["RUN", "ERR", "LINK", "1.yellow"])
def test_led_lit_samples_match_the_pattern_shown(chunks: Chunks, led: str) -> None:
    """Lit (1) / dark (0) follows the ETG.1300 timing of the pattern the lane shows."""
    path = f"rig/fastcat/led/{led}"
    lane = rows(chunks, path, "StateChange:state")
    lit = rows(chunks, path, "Scalars:scalars")
    assert len(lit) > 2
    for t, value in lit:
        assert value == float(is_lit(LedPattern(value_at(lane, t)), t)), (t, value)


def test_blinking_led_is_sampled_fast_enough_to_blink(chunks: Chunks) -> None:
    """RUN blinks (200 ms on / 200 ms off) in PREOP after the unplug: both phases recorded."""
    lit = [v for t, v in rows(chunks, "rig/fastcat/led/RUN", "Scalars:scalars") if t > 4.2 * S]
    assert lit.count(0.0) >= 4 and lit.count(1.0) >= 4


def test_process_data_follows_the_rig(chunks: Chunks) -> None:
    di = rows(chunks, "rig/fastcat/io/1/di", "Scalars:scalars")
    assert len(di[0][1]) == 16
    assert value_at(di, int(3.5 * S) - 1)[2] == 0.0
    assert value_at(di, int(3.6 * S))[2] == 1.0  # channel 3 as printed = index 2
    position = [(t, v[0]) for t, v in rows(chunks, "rig/fastcat/io/7/position",
                                               "Scalars:scalars")]
    after = [v for t, v in position if t >= 3.6 * S]
    assert after == sorted(after) and after[-1] > after[0]


def test_high_rate_signals_are_sent_in_batches(chunks: Chunks) -> None:
    """The spinning encoder changes at every 10 ms sample, yet goes out as one column batch
    per flush period, not one message per sample."""
    position = rows(chunks, "rig/fastcat/io/7/position", "Scalars:scalars")
    assert len(position) >= 200
    batches = [b for b in chunks["rig/fastcat/io/7/position"] if "sim_time" in b.schema.names]
    assert len(batches) <= 6 * S // FLUSH_US + 2


def test_unchanged_signals_cost_almost_nothing(chunks: Chunks) -> None:
    """DO16 outputs never change: first sample, then the held value at the end."""
    do = rows(chunks, "rig/fastcat/io/3/do", "Scalars:scalars")
    assert len(do) <= 3
    assert do[-1][0] >= 6 * S - 10_000


def test_blueprint_lays_out_the_rig(run: Run) -> None:
    reader = RrdReader(str(run.path))
    (blueprint,) = reader.blueprints()
    views: dict[str, str] = {}
    for chunk in reader.stream(store=blueprint):
        batch = chunk.to_record_batch()
        if "ViewBlueprint:class_identifier" in batch.schema.names:
            kind = batch.column("ViewBlueprint:class_identifier").to_pylist()[0][0]
            name = batch.column("ViewBlueprint:display_name").to_pylist()[0][0]
            views[name] = kind
    assert views["Events"] == "TextLog"
    assert views["Device states"] == views["LED patterns"] == "StateTimeline"
    plots = {s.view for _, s in rig_signals(run.rig.snapshot(), 0)} | {
        "fastcat 2 DI16 digital"}  # module 2 was unplugged by the end
    assert {n for n, k in views.items() if k == "TimeSeries"} == plots


# ---- the recorder on its own ---------------------------------------------------------------------
def servo_snapshot(position: float, state: str) -> dict[str, Any]:
    return {"rig": "bench", "devices": {"axis": {
        "kind": "servo", "position": position, "velocity": 12.5, "following_error": 0.25,
        "ds402_state": state, "statusword": 0x0237}}}


def test_drive_signals_and_state(tmp_path: Path) -> None:
    path = tmp_path / "servo.rrd"
    with RigRecorder(path) as recorder:
        for i in range(50):
            t = i * 10_000
            state = "SWITCH_ON_DISABLED" if i < 20 else "OPERATION_ENABLED"
            recorder.observe(t, servo_snapshot(float(i), state), [])
    chunks = load(path)
    assert [v for _, v in rows(chunks, "rig/axis/drive/position", "Scalars:scalars")] == [
        float(i) for i in range(50)]
    assert rows(chunks, "rig/axis/drive/following_error", "Scalars:scalars")[0] == (0, 0.25)
    assert rows(chunks, "rig/axis/drive/velocity", "Scalars:scalars")
    assert rows(chunks, "rig/axis/state/ds402", "StateChange:state") == [
        (0, "SWITCH_ON_DISABLED"), (200_000, "OPERATION_ENABLED")]


def test_samples_only_at_the_sampling_rate(tmp_path: Path) -> None:
    recorder = RigRecorder(tmp_path / "r.rrd", sample_period_us=20_000)
    due = []
    for t in range(0, 100_000, 1_000):  # a 1 ms simulation step
        if recorder.sample_due(t):
            due.append(t)
            recorder.observe(t, servo_snapshot(t, "X"), [])
    recorder.close()
    assert due == [0, 20_000, 40_000, 60_000, 80_000]


def test_a_module_of_another_width_starts_a_new_column(tmp_path: Path) -> None:
    """A module swapped for one with more channels: both widths stay in the recording."""
    def snap(di: list[bool]) -> dict[str, Any]:
        return {"rig": "r", "devices": {"fc": {"kind": "fastcat", "leds": {},
                                               "rail": [{"slot": 1, "type": "X", "di": di}]}}}

    path = tmp_path / "swap.rrd"
    with RigRecorder(path) as recorder:
        recorder.observe(0, snap([True, False]), [])
        recorder.observe(10_000, snap([True, False, True]), [])
    assert rerun_cli("rrd", "verify", str(path)).returncode == 0
    assert [v for _, v in rows(load(path), "rig/fc/io/1/di", "Scalars:scalars")] == [
        [1.0, 0.0], [1.0, 0.0, 1.0]]


@pytest.mark.filterwarnings("ignore:RRD file has no footer")
def test_download_mid_run_then_close(tmp_path: Path) -> None:
    path = tmp_path / "live.rrd"
    recorder = RigRecorder(path)
    for i in range(30):
        recorder.observe(i * 10_000, servo_snapshot(float(i), "OPERATION_ENABLED"),
                         [LogLine(i * 10_000, "axis", text=f"line {i}")])
    copy = tmp_path / "download.rrd"
    copy.write_bytes(recorder.recording_bytes())
    texts = rows(load(copy), "rig/axis/events", "TextLog:text")
    assert [t for _, t in texts] == [f"line {i}" for i in range(30)]
    # Still being written: a stream without the footer, which the viewer loads.
    assert rerun_cli("rrd", "verify", "--check-footers=false", str(copy)).returncode == 0
    recorder.close()
    recorder.close()  # idempotent
    recorder.observe(1 * S, servo_snapshot(1.0, "X"), [])  # after close: ignored
    assert rerun_cli("rrd", "verify", str(path)).returncode == 0


@pytest.mark.parametrize("kwargs", [{"sample_period_us": 0}, {"flush_period_us": -1},
                                    {"chunk_rows": 0},
                                    {"max_buffered_rows": 0}])
def test_bad_settings_are_refused(tmp_path: Path, kwargs: dict[str, int]) -> None:
    with pytest.raises(ValueError, match="positive"):
        RigRecorder(tmp_path / "x.rrd", **kwargs)


# Event lines: (event, text, level). The AL status meaning comes from the seed 000 §7.7 table.
EVENT_LINES = [
    (StateChanged(0, "d", from_state="INIT", to_state="PREOP"), "state: INIT -> PREOP", "INFO"),
    (StateChanged(0, "d", from_state="A", to_state="B", machine="ds402"), "ds402: A -> B",
     "INFO"),
    (EmergencySent(0, "d", code=0xFF00, register=0x81, data=bytes([2, 0, 0, 4, 0])),
     "EMCY 0xFF00 register 0x81 data [02 00 00 04 00]", "WARN"),
    (EmergencySent(0, "d", code=0, register=0, data=bytes(5)),
     "EMCY 0x0000 register 0x00 data [00 00 00 00 00]", "INFO"),
    (AlStatusChanged(0, "d", code=0x001B), "AL status code 0x001B: Sync manager watchdog",
     "WARN"),
    (AlStatusChanged(0, "d", code=0x8204), "AL status code 0x8204: Manufacturer specific",
     "WARN"),
    (AlStatusChanged(0, "d", code=0), "AL status code 0x0000: No error", "INFO"),
    (AlarmChanged(0, "d", code="0x04", name="MISSING_NODE_ANSWER", active=True, module=2),
     "alarm 0x04 MISSING_NODE_ANSWER raised (module 2)", "ERROR"),
    (AlarmChanged(0, "d", code="0x04", name="MISSING_NODE_ANSWER", active=False),
     "alarm 0x04 MISSING_NODE_ANSWER cleared", "INFO"),
    (LedChanged(0, "d", led="ERR", pattern="blinking"), "LED ERR: blinking", "INFO"),
    (LogLine(0, "master", text="hello", port=65535), "[port 65535] hello", "INFO"),
    (Caption(0, "scenario", text="Pull the cable"), "caption: Pull the cable", "INFO"),
    (Checkpoint(0, "scenario", name="cut"), "checkpoint: cut", "INFO"),
    (ValueRead(0, "fc", address="0x1008:0", value="FastCAT"), "read 0x1008:0 = FastCAT",
     "INFO"),
]


@pytest.mark.parametrize(("event", "text", "level"), EVENT_LINES,
                         ids=[f"{e.kind}-{i}" for i, (e, _, _) in enumerate(EVENT_LINES)])
def test_event_lines(event: Event, text: str, level: str) -> None:
    record = event.to_record()
    assert event_text.text(event, record) == text
    assert event_text.level(event, record) == level
    assert event_text.log_path(event) == f"rig/{event.device}/events"


def test_drive_signals_get_a_plot_each() -> None:
    """Position, velocity, following error and each word have different scales: one plot
    each (the statusword a step plot: test_recording_drive_io.py)."""
    views = {s.view: s.path for _, s in rig_signals(servo_snapshot(1.0, "X"), 0)}
    assert views == {"axis position": "rig/axis/drive/position",
                     "axis velocity": "rig/axis/drive/velocity",
                     "axis following error": "rig/axis/drive/following_error",
                     "axis statusword": "rig/axis/drive/statusword"}


# ---- the live runtime ----------------------------------------------------------------------------
def wait_for(predicate: Callable[[], bool], timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.01)


def test_attach_to_runtime_records_a_live_rig(tmp_path: Path) -> None:
    path = tmp_path / "live.rrd"
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    runtime = Runtime(rig, speed=20.0)
    recorder = RigRecorder(path)
    attach_to_runtime(runtime, recorder)
    runtime.start()
    try:
        runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        wait_for(lambda: runtime.frame.t_us >= int(3.5 * S))
    finally:
        runtime.stop()
        recorder.close()
    assert rerun_cli("rrd", "verify", str(path)).returncode == 0
    chunks = load(path)
    lane = rows(chunks, "rig/fastcat/state", "StateChange:state")
    assert [v for _, v in lane][:4] == ["INIT", "PREOP", "SAFEOP", "OP"]
    assert rows(chunks, "rig/fastcat/led/LINK", "Scalars:scalars")
    assert rows(chunks, "rig/fastcat/io/1/di", "Scalars:scalars")
    assert not math.isnan(rows(chunks, "rig/fastcat/io/4/ai", "Scalars:scalars")[0][1][0])


def test_live_recording_samples_a_quiet_rig(tmp_path: Path) -> None:
    """In OP nothing happens, yet LINK flickers (ETG.1300, 50/50 ms): the samples show it."""
    path = tmp_path / "quiet.rrd"
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    runtime = Runtime(rig, speed=5.0)
    recorder = RigRecorder(path)
    attach_to_runtime(runtime, recorder)
    runtime.start()
    try:
        runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        wait_for(lambda: runtime.frame.t_us >= 4 * S)
    finally:
        runtime.stop()
        recorder.close()
    link = rows(load(path), "rig/fastcat/led/LINK", "Scalars:scalars")
    quiet = [v for t, v in link if 3.3 * S <= t <= 3.9 * S]
    assert quiet.count(0.0) >= 5 and quiet.count(1.0) >= 5


def test_a_restarted_rig_continues_the_timeline(tmp_path: Path) -> None:
    """A scenario loaded on the dashboard restarts the rig clock at 0: the recording goes on
    after the last run (one sample period apart) with a full sample, never back in time."""
    from app.player import reset_in_place

    path = tmp_path / "restart.rrd"
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    recorder = RigRecorder(path, flush_period_us=FLUSH_US)
    hook = scenario_observer(recorder)
    rig.apply("fastcat", "power", {"on": True})
    hook(rig, rig.take_events())
    while rig.clock.now_us < 2 * S:
        hook(rig, rig.step())
    first_end = rig.clock.now_us
    reset_in_place(rig, build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    assert rig.clock.now_us == 0
    while rig.clock.now_us < S:
        hook(rig, rig.step())
    recorder.close()
    assert recorder.runs == 2
    assert rerun_cli("rrd", "verify", str(path)).returncode == 0
    chunks = load(path)
    restart = rows(chunks, event_text.RIG_LOG, "TextLog:text")
    assert len(restart) == 1 and "run 2" in restart[0][1]
    second_start = restart[0][0]
    assert second_start >= first_end + recorder.sample_period_us - 1_000
    run_led = rows(chunks, "rig/fastcat/led/RUN", "StateChange:state")
    # The fresh, unpowered rig's state is recorded again at the start of run 2 (a lane keeps
    # changes only: this row exists because the restart starts with a full sample).
    assert [t for t, _ in run_led if second_start <= t < second_start + 20_000]
    assert value_at(run_led, second_start) == run_led[0][1]
    assert max(t for t, _ in run_led) <= second_start + S


def test_led_names_with_spaces_and_slashes_stay_one_part(tmp_path: Path) -> None:
    """The TRS-CAT's "LINK-ACT IN" and "I/O 1" LEDs: one entity each, no nesting, no warning."""
    from app.recording.signals import device_path

    assert device_path("trscat", "led", "I/O 1") == "rig/trscat/led/I\\/O\\ 1"
    assert device_path("fastcat", "led", "2.yellow") == "rig/fastcat/led/2.yellow"


def test_drive_plots_start_afresh_at_a_load() -> None:
    """The dashboard's drive plots (app/ui/drive/plots.py) follow a scenario load (the rig's
    load count) the way the recorder does: the old run's samples go, the new run's start at
    0 (tests/app/test_event_log_restart.py: a load at 0 s, two loads in a row)."""
    from app.ui.drive.plots import SAMPLE_US, DriveSampler

    loads = [0]
    sampler = DriveSampler(lambda: {"position_counts": 1, "velocity": 2, "following_error": 0},
                           loads=lambda: loads[0])
    for t_us in range(0, 2 * S, 1000):
        sampler.on_step(t_us)
    assert len(sampler.columns()[0]) == 2 * S // SAMPLE_US
    loads[0] += 1
    for t_us in range(0, 100_000, 1000):
        sampler.on_step(t_us)
    times = sampler.columns()[0]
    assert list(times) == [i * SAMPLE_US / 1e6 for i in range(100_000 // SAMPLE_US)]
