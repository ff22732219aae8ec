"""Every state machine lane holds the state the rig started in, not only the changes.

docs/recording.md says the ``rig/<device>/state/<machine>`` lanes take events and samples. An
audit of the example scenarios' recordings found four of them fed by events only, their
state nested in the snapshot where the sampler did not look: the TRS-CAT's TRS bus and sync
unit (``trs_bus.state``, ``sync.state``), the FastCAT's CNF button and procedure
(``cnf.pressed``, ``cnf.phase``) and the master's DC unit (``dc.state``). So the sync lane
began at 0.351 s with ``dc_running``, the master's DC lane at 1 ms, and a CNF lane only at the
first press: nothing said the sync unit was in ``free_run`` or the DC unit ``IDLE`` before.
"""

from __future__ import annotations

import pytest
from test_recording import Run, load, rows, value_at

from devices.events import StateChanged

S = 1_000_000
LANES = [("trscat", "trs_bus"), ("trscat", "sync"), ("fastcat", "cnf"),
         ("fastcat", "cnf_button"), ("master", "dc")]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "machines.rrd")
    r.hook(r.rig, r.rig.take_events())  # t = 0, as run_scenario starts
    r.run_until(1 * S)
    r.do("fastcat", "hold_cnf", seconds=0.5)  # a short press: the button moves, nothing else
    r.run_until(2 * S)
    r.recorder.close()
    return r


def snapshot_value(run: Run, device: str, machine: str) -> str:
    snap = run.rig.snapshot()["devices"][device]
    return {"trs_bus": lambda: snap["trs_bus"]["state"], "sync": lambda: snap["sync"]["state"],
            "cnf": lambda: snap["cnf"]["phase"], "dc": lambda: snap["dc"]["state"],
            "cnf_button": lambda: "pressed" if snap["cnf"]["pressed"] else "released"}[machine]()


@pytest.mark.parametrize(("device", "machine"), LANES)
def test_lane_starts_at_zero_and_holds_every_change(run: Run, device: str, machine: str) -> None:
    lane = rows(load(run.path), f"rig/{device}/state/{machine}", "StateChange:state")
    assert lane and lane[0][0] == 0, lane
    changes = [e for e in run.events if isinstance(e, StateChanged)
               and e.device == device and e.machine == machine]
    if changes and changes[0].t_us > 0:
        assert lane[0][1] == changes[0].from_state
    for event in changes:
        assert (event.t_us, event.to_state) in lane, (event, lane)
    assert value_at(lane, run.rig.clock.now_us) == snapshot_value(run, device, machine)


def test_the_button_press_is_on_its_lane(run: Run) -> None:
    lane = rows(load(run.path), "rig/fastcat/state/cnf_button", "StateChange:state")
    assert [v for _, v in lane] == ["released", "pressed", "released"]
