"""The served-rigs benchmark runs real runtimes and reads their clocks and CPU."""

from __future__ import annotations

from app.rig_config import DEFAULT_RIG, load_rig_spec
from bench.served import served


def test_served_rigs_keep_their_clocks_and_report_cpu() -> None:
    spec = load_rig_spec(DEFAULT_RIG)
    for busy in (False, True):
        pace, per_ms = served(spec, 1, 1.0, busy)
        # the runtime keeps the rig on the wall clock (a loaded machine may lag a little)
        assert 0.5 < pace <= 1.05
        assert per_ms > 0


def test_recorded_rigs_keep_their_clocks_both_ways() -> None:
    spec = load_rig_spec(DEFAULT_RIG)
    for repeat in (True, False):
        pace, per_ms = served(spec, 1, 1.0, False, record=repeat)
        assert 0.5 < pace <= 1.05
        assert per_ms > 0
