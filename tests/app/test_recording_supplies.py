"""Supply voltages and the TRS bus current are recorded (docs/recording.md).

cpx_output_supply_low lowers the CPX-E-EC's U_OUT (seed 002 Tab. 29: 24 V +- 25 %), and the
TRS-CAT's field supply (seed 001 §10.3: 18..30 V) turns its +24V LED off: the snapshots carry
the voltages (``supply.el_sen_v`` / ``out_v``, ``field_supply_v``) and the TRS bus current
(``trs_bus.current_a``), but an audit of the example scenarios' recordings found none of them:
a replay showed the PL LED go off with no voltage behind it.
"""

from __future__ import annotations

import pytest
from test_recording import Run, load, rows, value_at

S = 1_000_000


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "supplies.rrd")
    r.hook(r.rig, r.rig.take_events())  # t = 0, as run_scenario starts
    r.run_until(1 * S)
    r.do("cpx", "supply", out=16.5)
    r.do("trscat", "field_supply", volts=17.0)
    r.run_until(1_500_000)
    r.recorder.close()
    return r


def test_supplies_follow_the_snapshot(run: Run) -> None:
    chunks = load(run.path)
    devices = run.rig.snapshot()["devices"]
    now = run.rig.clock.now_us
    cpx = rows(chunks, "rig/cpx/supply", "Scalars:scalars")
    assert cpx[0] == (0, [24.0, 24.0])
    assert value_at(cpx, now) == [devices["cpx"]["supply"]["el_sen_v"], 16.5]
    trs = rows(chunks, "rig/trscat/supply", "Scalars:scalars")
    assert trs[0] == (0, 24.0)
    assert value_at(trs, now) == 17.0
    current = rows(chunks, "rig/trscat/trs_bus/current_a", "Scalars:scalars")
    assert current and current[0][0] == 0
    assert value_at(current, now) == devices["trscat"]["trs_bus"]["current_a"]
