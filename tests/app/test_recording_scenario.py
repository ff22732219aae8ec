"""A recording names the scenario it shows (docs/recording.md "Which scenario"): a handed-over
``.rrd`` said only the rig's name, and no row named the scenario, so nobody could tell which
demo it was. ``scenario run --record`` puts the scenario's name in the recording's name and a
row at its start; a load in the dashboard's player names it in its run row."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

from rerun.chunk import RrdReader

from app.cli import main
from app.player import Player
from app.recording import RigRecorder, attach_to_runtime, event_text
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import load_scenario

SCENARIO = """[scenario]
name = "Sales demo: power-up"
duration_s = 1

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true
"""
WAIT_S = 60.0


def recording_names(path: Path) -> list[str]:
    reader = RrdReader(str(path))
    names: list[str] = []
    for chunk in reader.stream(store=reader.recordings()[0]):
        batch = chunk.to_record_batch()
        if "RecordingInfo:name" in batch.schema.names:
            names.extend(v[0] for v in batch.column("RecordingInfo:name").to_pylist())
    return names


def session_rows(path: Path) -> list[tuple[int, str]]:
    reader = RrdReader(str(path))
    rows: list[tuple[int, str]] = []
    for chunk in reader.stream(store=reader.recordings()[0]):
        if chunk.entity_path.lstrip("/") != event_text.RIG_LOG:
            continue
        batch = chunk.to_record_batch()
        rows.extend((t // dt.timedelta(microseconds=1), v[0]) for t, v in zip(
            batch.column("sim_time").to_pylist(), batch.column("TextLog:text").to_pylist(),
            strict=True))
    return sorted(rows)


def test_scenario_run_record_names_the_scenario(tmp_path: Path) -> None:
    path = tmp_path / "demo.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    record = tmp_path / "demo.rrd"
    assert main(["scenario", "run", str(path), "--quiet", "--record", str(record)]) == 0
    assert recording_names(record) == ["FieldRig default rig · Sales demo: power-up"]
    assert session_rows(record) == [(0, "run 1: scenario 'Sales demo: power-up'")]


def test_each_load_in_the_player_names_the_scenario_in_its_run_row(tmp_path: Path) -> None:
    path = tmp_path / "demo.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    scenario = load_scenario(path)
    record = tmp_path / "served.rrd"
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    recorder = RigRecorder(record)
    attach_to_runtime(runtime, recorder)
    runtime.start()
    try:
        runtime.advance(200_000).result(timeout=WAIT_S)  # served a while before any load
        player = Player(runtime)
        player.load(scenario)
        player.step()
        player.restart()
        player.step()
        runtime.submit(lambda: None).result(timeout=WAIT_S)
    finally:
        runtime.stop()
        recorder.close()
    assert recording_names(record) == ["FieldRig default rig"]  # served before any scenario
    texts = [text for _, text in session_rows(record)]
    assert len(texts) == 2, texts
    assert all(t.startswith(f"run {n}: the rig restarted") for n, t in zip((2, 3), texts,
                                                                           strict=True)), texts
    assert all(t.endswith(": scenario 'Sales demo: power-up'") for t in texts), texts
