"""A drive's fieldbus sides record under the drive: ``rig/<drive>/state/esm`` and ``.../nmt``.

The CoE slave (``<drive>-ecat``) and the CANopen node (``<drive>-can``) are models of their own
but emit under the drive's id (docs/architecture.md "Event schema"), so their ``state`` events
(``machine`` "esm" / "nmt") land on ``rig/<drive>/state/esm`` and ``rig/<drive>/state/nmt``. An
audit of the example scenarios' recordings found their samples elsewhere: the CoE slave's ESM
under ``rig/drive_ec-ecat/state`` (a path docs/recording.md does not name, a second ESM lane of
the same drive), and the CANopen node's NMT state not sampled at all, so neither lane under the
drive held the state the drive powered up in, only the changes after it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_recording import Chunks, Run, load, rows, value_at

from app.recording import RigRecorder
from devices.events import StateChanged

S = 1_000_000


def sides(esm: str, nmt: str, active: bool = True) -> dict[str, Any]:
    return {"rig": "bench", "devices": {
        "axis": {"kind": "servo", "ds402_state": "Switch on disabled"},
        "axis-ecat": {"kind": "servo_ecat", "drive": "axis", "esm": esm, "al_status_code": 0},
        "axis-can": {"kind": "canopen", "drive": "axis", "active": active, "nmt": nmt}}}


def test_side_samples_and_events_share_the_drive_lanes(tmp_path: Path) -> None:
    path = tmp_path / "sides.rrd"
    with RigRecorder(path) as recorder:
        recorder.observe(0, sides("INIT", "Pre-operational"), [])
        recorder.observe(4_601, None, [
            StateChanged(4_601, "axis", "INIT", "PREOP", machine="esm"),
            StateChanged(4_601, "axis", "Pre-operational", "Operational", machine="nmt")])
        recorder.observe(10_000, sides("PREOP", "Operational"), [])
    chunks = load(path)
    assert rows(chunks, "rig/axis/state/esm", "StateChange:state") == [
        (0, "INIT"), (4_601, "PREOP")]
    assert rows(chunks, "rig/axis/state/nmt", "StateChange:state") == [
        (0, "Pre-operational"), (4_601, "Operational")]
    assert not [p for p in chunks if p.startswith(("rig/axis-ecat", "rig/axis-can"))]


def test_a_silent_can_node_has_no_nmt_lane(tmp_path: Path) -> None:
    """A drive not on CANopen has a node that never speaks ("Off", c9 != 5): no lane."""
    path = tmp_path / "silent.rrd"
    with RigRecorder(path) as recorder:
        recorder.observe(0, sides("INIT", "Off", active=False), [])
    assert not rows(load(path), "rig/axis/state/nmt", "StateChange:state")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "sides.rrd")
    r.hook(r.rig, r.rig.take_events())  # t = 0, as run_scenario starts
    r.run_until(4 * S)  # drive_ec-ecat walks to OP, drive_co-can boots to Pre-operational
    r.recorder.close()
    return r


@pytest.mark.parametrize(("drive", "machine"), [("drive_ec", "esm"), ("drive_co", "nmt")])
def test_default_rig_side_lanes_start_at_power_up(run: Run, drive: str, machine: str) -> None:
    chunks: Chunks = load(run.path)
    lane = rows(chunks, f"rig/{drive}/state/{machine}", "StateChange:state")
    changes = [e for e in run.events
               if e.kind == "state" and e.device == drive and e.machine == machine]
    # The state before the first change is there: the ESM's INIT from 0 s; the node's
    # Initialisation from the first sample after it powered up (no event says it: the
    # node starts there, devices/canopen/node.py), before its boot-up to Pre-operational.
    assert changes and lane and lane[0][0] < changes[0].t_us, lane
    assert lane[0][1] == changes[0].from_state
    for event in changes:
        assert (event.t_us, event.to_state) in lane
    side = run.rig.snapshot()["devices"][f"{drive}-{'ecat' if machine == 'esm' else 'can'}"]
    assert value_at(lane, run.rig.clock.now_us) == side[machine]
    assert not [p for p in chunks if p.startswith(f"rig/{drive}-")]
