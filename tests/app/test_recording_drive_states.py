"""A servo drive's CiA 402 machine is one lane, ``rig/<drive>/state/ds402`` (docs/recording.md).

A drive's main state machine is CiA 402 (docs/architecture.md "machine values": its `state`
events carry no `machine`), and its snapshot gives it as ``ds402_state``. The lane must take
both: the samples (the state at power-up) and the events (every change at its own time, the
1 ms "Fault reaction active" between two samples included). A support walkthrough of
cable_pulled found them split: the events under ``rig/drive_ec/state`` (no initial state), the
samples under ``rig/drive_ec/state/ds402`` (no "Fault reaction active", the fault 9 ms late).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_recording import Chunks, Run, load, rows, value_at

from app.recording import RigRecorder
from devices.events import StateChanged

S = 1_000_000


def servo(state: str) -> dict[str, Any]:
    return {"rig": "bench", "devices": {"axis": {"kind": "servo", "ds402_state": state}}}


def test_drive_state_events_and_samples_share_the_ds402_lane(tmp_path: Path) -> None:
    path = tmp_path / "drive.rrd"
    with RigRecorder(path) as recorder:
        recorder.observe(0, servo("Switch on disabled"), [])
        recorder.observe(4_601, None, [
            StateChanged(4_601, "axis", from_state="Switch on disabled",
                         to_state="Fault reaction active"),
            StateChanged(4_601, "axis", from_state="Fault reaction active", to_state="Fault")])
        recorder.observe(10_000, servo("Fault"), [])
    chunks = load(path)
    assert rows(chunks, "rig/axis/state/ds402", "StateChange:state") == [
        (0, "Switch on disabled"), (4_601, "Fault reaction active"), (4_601, "Fault")]
    assert not rows(chunks, "rig/axis/state", "StateChange:state")


@pytest.fixture(scope="module")
def cable_pulled(tmp_path_factory: pytest.TempPathFactory) -> tuple[Run, Chunks]:
    run = Run(tmp_path_factory.mktemp("rec") / "line.rrd")
    run.run_until(4 * S)  # the line in OP
    run.do("master", "pull_cable", cable=2)  # drive_ec loses its master: alarm 34
    run.run_until(5 * S)
    run.recorder.close()
    return run, load(run.path)


def test_every_drive_state_event_is_on_its_lane_at_its_time(
        cable_pulled: tuple[Run, Chunks]) -> None:
    run, chunks = cable_pulled
    changes = [e for e in run.events if e.kind == "state" and e.device == "drive_ec"
               and not e.machine]
    assert any(e.to_state == "Fault" for e in changes)
    lane = rows(chunks, "rig/drive_ec/state/ds402", "StateChange:state")
    for event in changes:
        assert (event.t_us, event.to_state) in lane, (event, lane)
    assert value_at(lane, changes[-1].t_us) == "Fault"
    assert not rows(chunks, "rig/drive_ec/state", "StateChange:state")
