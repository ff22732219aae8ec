"""A scenario load starts a new run of the recording whatever the clock reads.

The recorder used to see a load only as the rig clock going back. A load while the clock is
still at 0 s (a scenario picked right after start, Restart before Play, two loads in a row)
puts nothing back: the old run's rows and the new run's were joined at the same times, and
the new run got no full first sample. The rig counts its loads (``Rig.loads``, bumped by
app/player.py ``reset_in_place``), and the recorder follows that count.
"""

from __future__ import annotations

from pathlib import Path

from test_recording import FLUSH_US, S, load, rows, value_at

from app.player import Player, reset_in_place
from app.recording import RigRecorder, attach_to_runtime, event_text, scenario_observer
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import EXAMPLES_DIR, load_scenario

TIMEOUT_S = 60


def fresh() -> Rig:
    return build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)


def test_a_load_at_0_s_starts_a_new_run(tmp_path: Path) -> None:
    """The coupler powered at 0 s, then a scenario loaded before the clock moved: run 2
    starts one sample period later with the fresh (unpowered) rig's full sample."""
    path = tmp_path / "at0.rrd"
    rig = fresh()
    recorder = RigRecorder(path, flush_period_us=FLUSH_US)
    hook = scenario_observer(recorder)
    hook(rig, rig.take_events())
    rig.apply("fastcat", "power", {"on": True})
    hook(rig, rig.take_events())
    reset_in_place(rig, fresh())
    assert rig.clock.now_us == 0
    hook(rig, rig.take_events())
    while rig.clock.now_us < S:
        hook(rig, rig.step())
    recorder.close()
    assert recorder.runs == 2
    chunks = load(path)
    restart = rows(chunks, event_text.RIG_LOG, "TextLog:text")
    assert [t for t, _ in restart] == [recorder.sample_period_us], restart
    power = rows(chunks, "rig/fastcat/state", "StateChange:state")
    # The unpowered rig's state again at run 2's start (a full sample), not only changes.
    assert [t for t, _ in power if t == recorder.sample_period_us], power
    assert value_at(power, recorder.sample_period_us) == power[0][1]


def test_two_loads_in_a_row_are_two_runs(tmp_path: Path) -> None:
    """A run of 2 s, then two loads with no step between them (Restart clicked twice)."""
    path = tmp_path / "twice.rrd"
    rig = fresh()
    recorder = RigRecorder(path, flush_period_us=FLUSH_US)
    hook = scenario_observer(recorder)
    rig.apply("fastcat", "power", {"on": True})
    hook(rig, rig.take_events())
    while rig.clock.now_us < 2 * S:
        hook(rig, rig.step())
    first_end = rig.clock.now_us
    for _ in range(2):
        reset_in_place(rig, fresh())
        hook(rig, rig.take_events())
    while rig.clock.now_us < S:
        hook(rig, rig.step())
    recorder.close()
    assert recorder.runs == 3
    restart = rows(load(path), event_text.RIG_LOG, "TextLog:text")
    period = recorder.sample_period_us
    assert [(t, text.split(":")[0]) for t, text in restart] == [
        (first_end + period, "run 2"), (first_end + 2 * period, "run 3")]


def test_a_live_recorder_follows_the_players_loads(tmp_path: Path) -> None:
    """A served rig (attach_to_runtime) and the dashboard's player: a scenario loaded right
    after start and loaded again at once are two more runs, the clock never having moved."""
    path = tmp_path / "live.rrd"
    runtime = Runtime(fresh())
    runtime.set_paused(True)
    recorder = RigRecorder(path, flush_period_us=FLUSH_US)
    attach_to_runtime(runtime, recorder)
    player = Player(runtime)
    runtime.start()
    try:
        scenario = load_scenario(EXAMPLES_DIR / "cnf_scan.toml")
        player.load(scenario)
        player.restart()
        runtime.advance(100_000).result(timeout=TIMEOUT_S)
    finally:
        runtime.stop()
        recorder.close()
    assert recorder.runs == 3
    restart = rows(load(path), event_text.RIG_LOG, "TextLog:text")
    assert [text.split(":")[0] for _, text in restart] == ["run 2", "run 3"]
