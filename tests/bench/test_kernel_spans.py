"""The kernel benchmark's "advanced" figures advance the rigs as far as the stepped ones and
say how many steps the quiet spans skipped (bench/kernel.py run_spans)."""

from __future__ import annotations

from app.rig_config import build_rig, parse_rig_spec
from bench.kernel import BATCH_STEPS, boot, run_spans

RIG = """
[rig]
name = "small line"
seed = 2

[[fastcat]]
id = "fastcat"
modules = ["DB16", "DI16", "AO4"]
"""


def test_advanced_rigs_keep_time_and_skip_when_idle() -> None:
    rigs = [build_rig(parse_rig_spec(RIG, "<small>"), state_dir=None) for _ in range(2)]
    boot(rigs)
    start = [r.clock.now_us for r in rigs]
    cpu, share = run_spans(rigs, 0.5)
    assert [r.clock.now_us - t for r, t in zip(rigs, start, strict=True)] == [500_000] * 2
    assert cpu > 0 and 0.9 < share <= 1.0  # idle in OP: nearly every step skipped
    assert 500 % BATCH_STEPS == 0
