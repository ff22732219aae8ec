"""The recording keeps the line's injected causes, which the master's log no longer names
(docs/ethercat-master.md "What the master knows"): a lane ``rig/master/state/injected`` in
the Device states view, "none" on a healthy line (docs/recording.md)."""

from __future__ import annotations

from app.recording.signals import state_values
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec


def test_the_master_s_injected_causes_are_a_lane_of_the_recording() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.advance(8000)
    lanes = dict(state_values("master", rig.snapshot()["devices"]["master"]))
    assert lanes["rig/master/state/injected"] == "none"
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.advance(10)
    lanes = dict(state_values("master", rig.snapshot()["devices"]["master"]))
    assert lanes["rig/master/state/injected"] == "2: cable 2 pulled; 3: cable 2 pulled"
    # Only the master has the lane: a slave's snapshot has no injected line causes.
    assert not any(
        path.endswith("/injected")
        for path, _ in state_values("trscat", rig.snapshot()["devices"]["trscat"])
    )
