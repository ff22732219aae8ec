"""Quiet spans on whole rigs change nothing (docs/performance.md "Quiet spans").

``Rig.advance`` / ``Rig.run_until`` skip a span of steps only while every device of the rig is
quiet; the master then passes its slaves the span's frames in one go (devices/master/spans.py).
Exact or wrong: the same runs one step at a time (``SKIP_SPANS`` off on the instance) must give
the same events and the same deep state (tests/hardening/span_runs.py):

- every example scenario: events.jsonl lines and the snapshot at each checkpoint and the end;
- a seeded random differential on two default rigs: commands of every device family (faults
  injected and cleared, cables, power, DC faults, state targets, inputs, drives), with stretches
  of 1 .. 3000 steps between them, compared after each; the idle default rig must skip most of
  its steps.

Reduced (CI): two scenarios and 1 x 25 operations; ``--full``: every scenario, 3 x 300.
"""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from span_runs import Op, differential, plain, rig_state
from still_runs import checkpoint_run, scenario_rig
from test_still_steps import random_op as drive_op

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario

SCENARIOS = sorted((Path(DEFAULT_RIG).parent.parent / "scenarios").glob("*.toml"))
TRSCAT_FAULTS = ("TRS_OVERCURRENT", "FIELD_SUPPLY")
REDUCED = ("module_lost_in_op", "dc_sync_lost")


def scenario_run(path: Path, skip: bool) -> tuple[list[str], dict]:
    scenario = load_scenario(path)
    rig = scenario_rig(scenario)
    if not skip:
        plain(rig)
    return checkpoint_run(scenario, rig, rig_state)


@pytest.mark.parametrize("path", [
    p if p.stem in REDUCED else pytest.param(p, marks=pytest.mark.full)
    for p in SCENARIOS], ids=lambda p: p.stem)
def test_example_scenarios_are_the_same_without_spans(path: Path) -> None:
    assert scenario_run(path, True) == scenario_run(path, False)


def rig_op(rng: random.Random) -> Op:
    """A command to any device of the default rig (the drives' as in test_still_steps)."""
    choices = [
        lambda: ("master", "pull_cable", {"cable": rng.randrange(4)}),
        lambda: ("master", "plug_cable", {"cable": rng.randrange(4)}),
        lambda: ("master", "power_slave", {"position": rng.randrange(4),
                                           "on": rng.random() < 0.7}),
        lambda: ("master", "lose_frames", {"count": rng.choice((1, 3, 10))}),
        lambda: ("master", "dc_fault", {"kind": rng.choice(("drift", "jitter", "sync0_lost"))}),
        lambda: ("master", "clear_dc_fault", {}),
        lambda: ("master", "set_target", {"state": rng.choice(("PREOP", "SAFEOP", "OP", "OP"))}),
        lambda: ("master", "resync", {}),
        lambda: ("fastcat/2", "set_input", {"channel": rng.randint(1, 16),
                                          "value": rng.random() < 0.5}),
        lambda: ("fastcat", "inject_fault", {"fault": "MISSING_NODE_ANSWER"}),
        lambda: ("fastcat", "clear_fault", {"fault": "MISSING_NODE_ANSWER"}),
        lambda: ("fastcat/4", "inject_fault", {"fault": "TARATURA"}),
        lambda: ("fastcat/4", "clear_fault", {"fault": "TARATURA"}),
        lambda: ("trscat", "inject_fault", {"fault": rng.choice(TRSCAT_FAULTS)}),
        lambda: ("trscat", "clear_fault", {"fault": rng.choice(TRSCAT_FAULTS)}),
        lambda: ("fastcat", "set_reset_fault", {"on": rng.random() < 0.5}),
        lambda: ("fastcat", "press_cnf", {}),
        lambda: ("fastcat", "release_cnf", {}),
        lambda: ("fastcat/4", "unplug", {}),
        lambda: ("fastcat/4", "plug", {"type": "AI8D"}),
        lambda: ("fastcat/7", "set_shaft_speed", {"encoder": 1, "rpm": rng.choice((0.0, 60.0))}),
        lambda: ("trscat", "set_input", {"channel": rng.randint(1, 8),
                                         "on": rng.random() < 0.5}),
        lambda: ("trscat", "drop_frames", {"count": rng.choice((1, 50))}),
        lambda: ("trscat", "lose_sync0", {"lost": rng.random() < 0.5}),
        lambda: ("cpx/1", "set_input", {"channel": rng.randint(0, 15), "on": rng.random() < 0.5}),
        lambda: ("cpx", "inject_fault", {"fault": rng.choice(("watchdog", "sync_error",
                                                               "short_circuit"))}),
        lambda: ("cpx", "clear_fault", {"fault": rng.choice(("watchdog", "sync_error",
                                                              "short_circuit"))}),
        lambda: ("drive_ec-ecat", "link", {"connected": rng.random() < 0.7}),
        lambda: drive_op(rng),
    ]
    return rng.choice(choices)()


def booted() -> Rig:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.apply("fastcat", "power", {"on": True})
    return rig


@pytest.mark.parametrize("seed", [5, pytest.param(6, marks=pytest.mark.full),
                                  pytest.param(7, marks=pytest.mark.full)])
def test_random_differential_on_the_default_rig(seed: int, full: bool) -> None:
    skipped = differential(booted, rig_op, seed, 300 if full else 25, finale=HEAL,
                           finale_steps=1_000)
    assert skipped > 2_000  # at least the healed rig's last seconds


# Every fault the ops can leave behind, cleared: the line back to OP, the rig idle again.
HEAL: tuple[Op, ...] = (
    *(("master", "plug_cable", {"cable": c}) for c in range(4)),
    *(("master", "power_slave", {"position": p, "on": True}) for p in range(4)),
    ("master", "clear_dc_fault", {}), ("master", "set_target", {"state": "OP"}),
    ("fastcat", "clear_fault", {"fault": "MISSING_NODE_ANSWER"}),
    ("fastcat/4", "clear_fault", {"fault": "TARATURA"}),
    ("fastcat", "release_cnf", {}), ("fastcat/7", "set_shaft_speed", {"encoder": 1, "rpm": 0.0}),
    *(("trscat", "clear_fault", {"fault": f}) for f in TRSCAT_FAULTS),
    ("trscat", "lose_sync0", {"lost": False}),
    *(("cpx", "clear_fault", {"fault": f}) for f in ("watchdog", "sync_error", "short_circuit")),
    ("drive_ec-ecat", "link", {"connected": True}),
    *((d, "power", {"on": True}) for d in ("drive", "drive_co", "drive_ec")),
    *((d, "enable", {"on": False}) for d in ("drive", "drive_co", "drive_ec")),
    ("master", "resync", {}),
    ("fastcat", "set_reset_fault", {"on": True}), ("fastcat", "set_reset_fault", {"on": False}),
) + (("master", "set_target", {"state": "OP"}),) * 8


def test_the_idle_default_rig_skips_most_steps() -> None:
    rig = booted()
    rig.run_until(8_000_000)  # the scan, the line to OP, DC compensating
    skipped, t0 = rig.skipped_steps, rig.clock.now_us
    rig.run_until(t0 + 2_000_000)
    assert rig.skipped_steps - skipped > 1_500  # of 2,000 steps
