"""The master's view of each slave is recorded: its state lane and its error counters.

The master's snapshot carries, per line position (seed 003 diagnostic structure), the state it
reads (None while the slave does not answer), its counters (lost frames, working counter
errors, emergencies, state changes) and the ESC error counters 0x0300-0x0313. An audit of the
example scenarios' recordings found its ``slave_state`` events as text lines only and none of
the counters: a replay of cable_pulled showed the lost frames only as log lines and no plot of
a damaged cable's ESC errors. Now: ``rig/master/state/slave/<position>`` (events + samples,
"absent" while the slave does not answer) and ``rig/master/slave/<position>/counters`` /
``esc_errors`` (samples).
"""

from __future__ import annotations

import pytest
from test_recording import Run, load, rows, value_at

from devices.events import SlaveStateChange

S = 1_000_000


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "master.rrd")
    r.hook(r.rig, r.rig.take_events())  # t = 0, as run_scenario starts
    r.run_until(3 * S)  # the line in OP
    r.do("master", "lose_frames", count=3)
    r.run_until(3_500_000)
    r.do("master", "pull_cable", cable=3)  # drive_ec-ecat (position 3) stops answering
    r.run_until(4 * S)
    r.recorder.close()
    return r


def test_every_slave_state_event_is_on_its_lane(run: Run) -> None:
    chunks = load(run.path)
    events = [e for e in run.events if isinstance(e, SlaveStateChange)]
    assert {e.position for e in events} == {0, 1, 2, 3}
    for position in range(4):
        lane = rows(chunks, f"rig/master/state/slave/{position}", "StateChange:state")
        assert lane and lane[0][0] == 0, position
        for event in events:
            if event.position == position:
                assert (event.t_us, event.to_state) in lane, (event, lane)
    lost = rows(chunks, "rig/master/state/slave/3", "StateChange:state")
    assert value_at(lost, run.rig.clock.now_us) == "absent"


def test_counters_follow_the_snapshot(run: Run) -> None:
    chunks = load(run.path)
    now = run.rig.clock.now_us
    slaves = run.rig.snapshot()["devices"]["master"]["slaves"]
    assert any(s["counters"]["lost_frames"] for s in slaves)
    for slave in slaves:
        position = slave["position"]
        counters = rows(chunks, f"rig/master/slave/{position}/counters", "Scalars:scalars")
        assert counters and counters[0][0] == 0
        assert value_at(counters, now) == [float(v) for v in slave["counters"].values()]
        esc = rows(chunks, f"rig/master/slave/{position}/esc_errors", "Scalars:scalars")
        assert esc and esc[0][0] == 0
        flat = [float(x) for v in slave["esc_errors"].values()
                for x in (v if isinstance(v, list) else [v])]
        assert value_at(esc, now) == flat
