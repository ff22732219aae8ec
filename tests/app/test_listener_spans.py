"""Step listeners' quiet spans keep their promise: no step up to ``quiet_until`` would have
made them act (the recorder's samples, the drive plots' samples). Runtime.add_step_listener
uses them to let the rig skip (tests/app/test_runtime_spans.py)."""

from __future__ import annotations

from pathlib import Path

from test_recording import servo_snapshot

from app.recording.recorder import RigRecorder
from app.rig import FAR_US
from app.ui.drive.plots import SAMPLE_US, DriveSampler

STEP_US = 1_000


def test_the_recorder_has_nothing_due_before_its_next_sample(tmp_path: Path) -> None:
    recorder = RigRecorder(tmp_path / "r.rrd", sample_period_us=20_000)
    loads = [0]  # the rig's load count (Rig.loads)
    recorder.load_count = lambda: loads[0]
    assert recorder.quiet_until(0, STEP_US) == 0  # no sample yet: the first step takes one
    for t in range(0, 100_000, STEP_US):
        until = recorder.quiet_until(t, STEP_US)
        assert not any(recorder.sample_due(u) for u in range(t + STEP_US, until + 1, STEP_US))
        if recorder.sample_due(t):
            recorder.observe(t, servo_snapshot(t, "X"), [])
            assert recorder.quiet_until(t, STEP_US) == t + 20_000 - 1
    # A scenario loaded (the clock need not go back): no span until a step's observation
    # starts the new run.
    loads[0] += 1
    assert recorder.quiet_until(99_000, STEP_US) == 99_000
    assert recorder.sample_due(99_000)
    recorder.close()


def test_the_drive_sampler_has_nothing_due_before_its_next_sample() -> None:
    loads = [0]  # the rig's load count (Rig.loads)
    sampler = DriveSampler(lambda: {"position": 1.0}, loads=lambda: loads[0])
    assert sampler.quiet_until(0, STEP_US) == 0  # no timeline yet
    rows = []
    for t in range(STEP_US, 20 * SAMPLE_US, STEP_US):
        until = sampler.quiet_until(t - STEP_US, STEP_US)
        before = sampler.version
        sampler.on_step(t)
        rows.append(sampler.version > before)
        if t <= until:
            assert sampler.version == before, t  # a step inside the span took a sample
    assert sum(rows) >= 19
    last = 20 * SAMPLE_US - STEP_US
    assert sampler.quiet_until(last, STEP_US) > last
    loads[0] += 1  # a scenario loaded (the clock need not go back): a fresh timeline
    assert sampler.quiet_until(last, STEP_US) == last
    sampler.active = False
    assert sampler.quiet_until(0, STEP_US) == FAR_US
