"""Each EtherCAT slave's AL status code is a lane, ``rig/<device>/al_status`` (docs/recording.md).

The AL status code register (0x0134, seed 000 §7.7) is what a field engineer reads first
after a slave falls back from OP. The snapshots carry it (``al_status_code``) and every change
is an ``al_status`` event, but an audit of the example scenarios' recordings found it only as
event text lines: no lane showed which code a slave held at a given time, nor the code it
held before the first event. The lane takes both, as the ESM lane does: the samples (the code
at power-up) and the events (each change at its own time, to the microsecond). A drive's CoE
slave (``<drive>-ecat``) emits under the drive's id, so its code is under the drive.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_recording import Chunks, Run, load, rows, value_at

from app.recording import RigRecorder
from devices.events import AlStatusChanged, fmt_hex

S = 1_000_000


def slaves(code: int, drive_code: int) -> dict[str, Any]:
    return {"rig": "bench", "devices": {
        "io": {"kind": "trscat", "esm": "OP", "al_status_code": code},
        "axis": {"kind": "servo", "ds402_state": "Switch on disabled"},
        "axis-ecat": {"kind": "servo_ecat", "drive": "axis", "esm": "OP",
                      "al_status_code": drive_code}}}


def test_al_status_samples_and_events_share_one_lane(tmp_path: Path) -> None:
    path = tmp_path / "al.rrd"
    with RigRecorder(path) as recorder:
        recorder.observe(0, slaves(0, 0), [])
        recorder.observe(4_601, None, [AlStatusChanged(4_601, "io", code=0x001B),
                                       AlStatusChanged(4_601, "axis", code=0x001A)])
        recorder.observe(10_000, slaves(0x001B, 0x001A), [])
    chunks = load(path)
    assert rows(chunks, "rig/io/al_status", "StateChange:state") == [
        (0, "0x0000"), (4_601, "0x001B")]
    assert rows(chunks, "rig/axis/al_status", "StateChange:state") == [
        (0, "0x0000"), (4_601, "0x001A")]
    assert not [p for p in chunks if p.startswith("rig/axis-ecat")]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "al.rrd")
    r.do("fastcat", "power", on=True)
    r.run_until(int(3.5 * S))  # the coupler in OP (seed 000 §7)
    r.do("fastcat/2", "unplug")  # module lost in OP: back to SAFEOP with 0x8204 or such
    r.run_until(5 * S)
    r.recorder.close()
    return r


def test_every_al_status_event_is_on_the_lane_at_its_time(run: Run) -> None:
    chunks: Chunks = load(run.path)
    changes = [e for e in run.events if isinstance(e, AlStatusChanged)
               and e.device == "fastcat"]
    assert any(e.code for e in changes), "the unplug set no AL status code"
    lane = rows(chunks, "rig/fastcat/al_status", "StateChange:state")
    assert lane and lane[0] == (0, "0x0000"), lane
    for event in changes:
        assert (event.t_us, fmt_hex(event.code, 4)) in lane
    snap = run.rig.snapshot()["devices"]["fastcat"]
    assert value_at(lane, run.rig.clock.now_us) == fmt_hex(snap["al_status_code"], 4)
