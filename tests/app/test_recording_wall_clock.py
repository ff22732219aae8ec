"""A scenario run's recording carries no wall-clock time (docs/recording.md "Timeline").

rerun-sdk 0.41 sends the recording's properties by default (``RecordingStream(...,
send_properties=True)``): a ``RecordingInfo:start_time`` row at ``/__properties`` with the
wall-clock instant the stream was made. Two runs of one scenario then differed in that value,
while the docs said nothing in a recording was stamped with the wall clock. A scenario run now
sends the name only; a served session keeps its start time (a live session's instant is what
its file name says too)."""

from __future__ import annotations

from pathlib import Path

import pytest
from rerun.chunk import RrdReader

from app.cli import main
from app.recording import RigRecorder
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec

SCENARIO = """[scenario]
name = "Wall clock"
duration_s = 0.05

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true
"""


def properties(path: Path) -> dict[str, list[object]]:
    """The recording's ``/__properties`` columns, as the SDK's reader gives them."""
    reader = RrdReader(str(path))
    found: dict[str, list[object]] = {}
    for chunk in reader.stream(store=reader.recordings()[0]):
        if chunk.entity_path != "/__properties":
            continue
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if name.startswith("RecordingInfo:"):
                found.setdefault(name, []).extend(batch.column(name).to_pylist())
    return found


def recording_id(path: Path) -> str:
    return RrdReader(str(path)).recordings()[0].recording_id


@pytest.fixture
def runs(tmp_path: Path) -> list[Path]:
    scenario = tmp_path / "wall.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    records = [tmp_path / "one.rrd", tmp_path / "two.rrd"]
    for record in records:
        assert main(["scenario", "run", str(scenario), "--quiet", "--record",
                     str(record)]) == 0
    return records


def test_a_scenario_run_records_no_start_time(runs: list[Path]) -> None:
    for record in runs:
        assert properties(record) == {
            "RecordingInfo:name": [["FieldRig default rig · Wall clock"]]}


def test_a_screenshot_run_records_no_start_time(tmp_path: Path) -> None:
    from app.screenshots import served_run  # --screenshots --record: the same scenario run

    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    with served_run(rig, record=str(tmp_path / "shots.rrd"), quiet=True):
        pass
    assert "RecordingInfo:start_time" not in properties(tmp_path / "shots.rrd")


def test_two_runs_of_a_scenario_are_two_recordings(runs: list[Path]) -> None:
    # Rerun shows files that share an application and recording id as one recording: a
    # derived id would merge a customer's run with the reference run opened beside it.
    assert recording_id(runs[0]) != recording_id(runs[1])


def test_a_served_session_keeps_its_start_time(tmp_path: Path) -> None:
    recorder = RigRecorder(tmp_path / "served.rrd")
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    recorder.observe(0, rig.snapshot(), [])
    recorder.close()
    found = properties(tmp_path / "served.rrd")
    assert set(found) == {"RecordingInfo:start_time", "RecordingInfo:name"}
