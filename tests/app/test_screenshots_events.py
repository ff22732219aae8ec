"""The events of a ``--screenshots`` run (the dashboard's player on a served runtime) are the
lines ``scenario run`` prints, byte for byte, and a ``--record`` of it records every one of
them (docs/scenarios.md "Screenshots for CI").

No browser: the events and the recording come from the served runtime and the player alone
(app/screenshots.py ``served_run`` and ``play``, which ``run_with_screenshots`` shoots
between). Rigs that power their devices when built have events at t = 0
before any step; the browser test of module_lost_in_op alone never saw them out of place, as
its first step is a command, which takes them in both paths.
"""

from __future__ import annotations

import datetime as dt
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from rerun.chunk import RrdReader

from app.out_paths import event_lines
from app.recording.event_text import log_path
from app.rig_config import build_rig, load_rig_spec
from app.scenario import EXAMPLES_DIR, load_scenario, run_scenario
from app.screenshots import play, served_run

SCENARIOS = ["cable_pulled", "too_many_analog", "module_lost_in_op"]


def text_rows(record: Path) -> Counter[tuple[str, int]]:
    """(entity, sim time in us) of every text-log row of the recording."""
    reader = RrdReader(str(record))
    found: Counter[tuple[str, int]] = Counter()
    for chunk in reader.stream(store=reader.recordings()[0]):
        batch = chunk.to_record_batch()
        if "TextLog:text" in batch.schema.names and "sim_time" in batch.schema.names:
            found.update((chunk.entity_path.lstrip("/"), t // dt.timedelta(microseconds=1))
                         for t in batch.column("sim_time").to_pylist())
    return found


def fresh(scenario_name: str) -> tuple[Any, Any]:
    scenario = load_scenario(EXAMPLES_DIR / f"{scenario_name}.toml")
    # The EtherCAT line's scenarios (cable_pulled) run on the default rig, which is that line.
    assert scenario.rig is not None or scenario_name in ("module_lost_in_op", "cable_pulled")
    rig_file = scenario.rig or str(EXAMPLES_DIR.parent / "rigs" / "default.toml")
    return scenario, build_rig(load_rig_spec(rig_file), state_dir=None)


def served_play(name: str, record: Path | None = None) -> tuple[Any, list[Any]]:
    """Play example ``name`` on its served rig: the scenario and the events journalled."""
    scenario, rig = fresh(name)
    checkpoints: list[str] = []
    with served_run(rig, record=None if record is None else str(record),
                    quiet=True) as (served, events):
        failures = play(served, scenario, rig, lambda step: checkpoints.append(step.text))
    assert failures == []
    assert checkpoints == [s.text for s in scenario.steps if s.kind == "checkpoint"]
    return scenario, events


@pytest.mark.parametrize("name", SCENARIOS)
def test_a_recording_of_a_served_play_has_every_event(
        name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import app.recording

    class SlowToOpen(app.recording.RigRecorder):
        """A recording file that takes a moment to open (a cold start of the CLI, a slow
        disk): the served rig must not run without the recorder meanwhile."""

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            time.sleep(0.5)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(app.recording, "RigRecorder", SlowToOpen)
    record = tmp_path / "run.rrd"
    _, events = served_play(name, record)
    assert any(e.t_us == 0 and e.to_record()["device"] != "scenario" for e in events)
    # Every event is a text-log row of its device, at its time (none lost at t = 0).
    wanted = Counter((log_path(e).lstrip("/"), e.t_us) for e in events)
    assert wanted - text_rows(record) == Counter()


@pytest.mark.parametrize("name", SCENARIOS)
def test_a_served_play_gives_the_lines_of_scenario_run(name: str) -> None:
    scenario, rig = fresh(name)
    expected = event_lines(run_scenario(scenario, rig).events)
    _, events = served_play(name)
    assert event_lines(events) == expected


def test_scenario_run_gives_events_in_time_order() -> None:
    """The events a rig emits when built come first, not inside the first step's, after the
    events at 1 ms of the devices before them (the served runtime cannot order them so)."""
    scenario, rig = fresh("cable_pulled")
    times = [e.t_us for e in run_scenario(scenario, rig).events]
    assert times == sorted(times)


def test_scenario_run_screenshots_writes_events_jsonl_once(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``events.jsonl`` has one owner, the CLI (it owns ``--out``: cleared before, written
    last and before stdout). With ``--screenshots`` run_with_screenshots wrote it, then the
    CLI again. The browser is a stand-in here: the pictures are not the point."""
    import os

    import app.screenshots
    from app.cli import main

    class NoBrowser:
        def __init__(self, _executable: str) -> None:
            pass

        def __enter__(self) -> NoBrowser:
            return self

        def __exit__(self, *_exc: object) -> None:
            pass

        def open(self, _served: object, show_player: bool = False) -> Any:
            return self

        def close(self) -> None:
            pass

    def shoot(_page: object, out: Path, number: int, step: Any) -> Path:
        path = out / app.screenshots.image_name(number, step.text)
        path.write_bytes(b"png")
        return path

    written: list[str] = []
    replace = os.replace

    def counted(src: Any, dst: Any) -> None:
        if Path(dst).name == "events.jsonl":
            written.append(str(dst))
        replace(src, dst)

    monkeypatch.setattr(app.screenshots, "Chromium", NoBrowser)
    monkeypatch.setattr(app.screenshots, "_shoot", shoot)
    monkeypatch.setattr(os, "replace", counted)
    out = tmp_path / "out"
    scenario = EXAMPLES_DIR / "module_lost_in_op.toml"
    assert main(["scenario", "run", str(scenario), "--out", str(out), "--screenshots",
                 "--quiet"]) == 0
    assert written == [str(out / "events.jsonl")]
    rig = build_rig(load_rig_spec(EXAMPLES_DIR.parent / "rigs" / "default.toml"), state_dir=None)
    expected = event_lines(run_scenario(load_scenario(scenario), rig).events)
    assert (out / "events.jsonl").read_text(encoding="utf-8") == expected
