"""The rig's revision: equal revisions mean a recording would sample the same thing, and
models marked ``QUIET_SNAPSHOT`` show the same snapshot.

``Rig.revision`` moves with every command, every outside write the runtime hands the rig
(``touch``) and every step the devices did not promise quiet (``quiet_steps``). A live
recorder repeats its last sample while it stands (docs/recording.md "Repeated samples"), so
the claim tested here is the one it relies on: two snapshots taken at the same revision give
the same state lanes and the same signals, each LED by its pattern (its lit / dark row is a
function of the pattern and the time alone). Counters the recording does not carry may move,
but not in a ``QUIET_SNAPSHOT`` model's snapshot: a snapshot that keeps those models from the
last one (``Rig.snapshot(since)``, the runtime's publication) must equal a fresh one.

- a seeded random differential on the default rig (the span tests' commands, faults healed at
  the end), driven as the runtime drives it: quiet spans skipped up to each 10 ms sample,
  the sample step taken, the claim checked at every sample with the revision unchanged;
- the rules, one by one, on small cases.

Reduced (CI): 1 x 25 operations; ``--full``: 3 x 300.
"""

from __future__ import annotations

import random
from collections.abc import Mapping
from typing import Any

import pytest
from span_runs import outcome
from test_spans_rig import HEAL, booted, rig_op

from app.recording.signals import rig_signals, state_values
from app.rig import Rig

SAMPLE_US = 10_000  # the recorder's default sample period


def recorded(snapshot: Mapping[str, Any]) -> tuple[Any, ...]:
    """What a recorder's sample takes from a snapshot, LEDs as patterns (not lit / dark)."""
    lanes = [v for d, s in snapshot["devices"].items() for v in state_values(d, s)]
    signals = [(s.path, s.pattern or s.values) for _d, s in rig_signals(snapshot, 0)]
    return tuple(lanes), tuple(signals)


def run_sampled(rig: Rig, steps: int, seen: dict[str, Any]) -> None:
    """``steps`` steps as the runtime takes them with a recorder attached: quiet spans skipped,
    through a sample time when the devices are quiet through it (Rig.quiet_span), else up to
    the step before it, which is stepped; at each sample, with the revision as at the last
    one, the recorded content must be the last one's."""
    step_us = rig.clock.step_us
    end = rig.clock.now_us + steps * step_us
    while rig.clock.now_us < end:
        now = rig.clock.now_us
        due = now - now % SAMPLE_US + SAMPLE_US
        span, observed = rig.quiet_span((end - now) // step_us,
                                        [lambda n, s, due=due: max(n, due - s)])
        if span:
            rig.skip(span)
            if not observed:
                continue
        else:
            rig.step()
        if rig.clock.now_us % SAMPLE_US:
            continue
        snapshot = rig.snapshot()
        content = recorded(snapshot)
        if rig.revision == seen.get("revision"):
            assert content == seen["content"], (rig.clock.now_us, "the same revision")
            kept = rig.snapshot(seen["snapshot"])  # QUIET_SNAPSHOT models from the last one
            assert kept == snapshot, (rig.clock.now_us, "a kept model snapshot moved")
            seen["repeats"] += 1
        seen["revision"], seen["content"], seen["snapshot"] = rig.revision, content, snapshot
        seen["samples"] += 1


@pytest.mark.parametrize("seed", [11, pytest.param(12, marks=pytest.mark.full),
                                  pytest.param(13, marks=pytest.mark.full)])
def test_an_unmoved_revision_records_the_same_sample(seed: int, full: bool) -> None:
    rng = random.Random(seed)
    rig = booted()
    seen: dict[str, Any] = {"repeats": 0, "samples": 0}
    run_sampled(rig, 6_000, seen)  # the scan and the line to OP
    plan = [(rig_op(rng), rng.choice((1, 3, 20, 200, 900, 3000)))
            for _ in range(300 if full else 25)]
    for op, steps in plan + [(op, 1_000) for op in HEAL]:
        outcome(rig, op)
        run_sampled(rig, steps, seen)
    # Not vacuous: the healed, idle rig repeats most of its samples.
    assert seen["repeats"] > 80 and seen["samples"] > seen["repeats"]


def idle_rig() -> Rig:
    rig = booted()
    rig.run_until(8_000_000)  # in OP, DC compensating: quiet for long spans
    return rig


def test_a_command_a_touch_and_an_unpromised_step_move_it() -> None:
    rig = idle_rig()
    before = rig.revision
    rig.apply("fastcat/2", "set_input", {"channel": 1, "value": True})
    assert rig.revision > before
    before = rig.revision
    rig.touch()
    assert rig.revision > before
    before = rig.revision
    rig.step()  # no promise since the touch
    assert rig.revision > before


def test_a_refused_command_moves_it_too() -> None:
    """A command may change a model before it refuses: the revision does not guess."""
    rig = idle_rig()
    before = rig.revision
    assert outcome(rig, ("fastcat/2", "set_input", {"channel": 99, "value": True})) \
        .startswith("refused")
    assert rig.revision > before


def test_promised_steps_and_skipped_spans_keep_it() -> None:
    rig = idle_rig()
    rig.touch()
    span = rig.quiet_steps(100)
    assert span >= 2
    before = rig.revision
    rig.skip(span - 1)
    rig.step()  # the span's last step, taken: promised
    assert rig.revision == before
    rig.apply("fastcat/2", "set_input", {"channel": 2, "value": True})
    moved = rig.revision
    rig.step()  # the promise went with the command
    assert rig.revision > moved


def test_a_busy_rig_moves_it_every_step() -> None:
    rig = booted()  # scanning its modules: nothing promised
    revisions = []
    for _ in range(50):
        rig.step()
        revisions.append(rig.revision)
    assert revisions == sorted(set(revisions))


def test_a_drive_left_standing_after_a_jog() -> None:
    """A drive disabled after a move stands still, but its RMS current (o2) decays through
    the quiet spans: its snapshot is not kept (QUIET_SNAPSHOT stays off for the drives)."""
    rig = idle_rig()
    rig.apply("drive", "enable", {"on": True})
    rig.apply("drive", "jog", {"direction": 1})
    rig.advance(500)
    rig.apply("drive", "stop", {})
    rig.advance(300)
    rig.apply("drive", "enable", {"on": False})
    seen: dict[str, Any] = {"repeats": 0, "samples": 0}
    run_sampled(rig, 5_000, seen)
    assert seen["repeats"] > 100


def test_a_new_ask_replaces_the_promise() -> None:
    """A model written to without a touch (a caller that broke the rule) says no at the next
    ask: the promise goes, and the next step moves the revision."""
    rig = idle_rig()
    assert rig.quiet_steps(100) >= 2
    rig.devices["drive"].apply("enable", {"on": True})  # the model's own API: no touch
    rig.devices["drive"].apply("jog", {"direction": 1})
    rig.take_events()  # the drive's events of the commands: not the step's
    assert rig.quiet_steps(100) == 0
    before = rig.revision
    for _ in range(10):  # a jog in progress: no event in these steps, and no promise
        assert rig.step() == []
    assert rig.revision == before + 10
