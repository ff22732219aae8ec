"""Every change of the TRS-CAT's sync machine is a StateChanged(machine="sync"), power-off too.

Switched off in OP under DC-SYNC, the sync unit is gone (its snapshot says free_run again): a
recording's sync lane and the event log must say so then, not only at the next change (whose
event then said "from": "free_run" while the lane still showed dc_running).
"""

from __future__ import annotations

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import EXAMPLES_DIR, load_scenario

SCENARIO = EXAMPLES_DIR / "trscat_expansion_mismatch.toml"


def test_power_off_reports_the_sync_machine_s_change() -> None:
    scenario = load_scenario(SCENARIO)
    rig = build_rig(load_rig_spec(scenario.rig or DEFAULT_RIG), state_dir=None)
    trscat = rig.devices["trscat"]
    rig.run_until(4_000_000)
    rig.take_events()
    assert trscat.snapshot()["sync"]["state"] == "dc_running"  # in OP, DC-SYNC
    rig.apply("trscat", "power", {"on": False})
    changes = [e.to_record() for e in rig.take_events()
               if e.to_record().get("machine") == "sync"]
    assert changes == [{"t": 4.0, "device": "trscat", "event": "state", "from": "dc_running",
                        "to": "free_run", "machine": "sync"}]
    assert trscat.snapshot()["sync"]["state"] == "free_run"
    rig.apply("trscat", "power", {"on": True})  # no change: no event
    assert not [e for e in rig.take_events() if e.to_record().get("machine") == "sync"]
