"""The field supply the snapshot reports is what a meter on the +24Vdc terminals reads: an
injected 0x3220 on the base (seed 001 §9.3.7) is that supply failing, as ``field_supply`` 0 V
(docs/trscat.md), so the reading says 0 V beside the +24V LED off (§8.4) and the set value
again once the fault is cleared."""

from __future__ import annotations

from trscat_bench import Bench

from devices.ethercat import AlState


def _reading(bench: Bench) -> tuple[float, bool, str]:
    snap = bench.trs.snapshot()
    return snap["field_supply_v"], snap["field_ok"], bench.leds()["+24V"]


def test_injected_field_supply_fault_on_the_base_reads_0_v_until_cleared() -> None:
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    bench.apply("field_supply", volts=26.0)
    bench.run(0.01)
    assert _reading(bench) == (26.0, True, "on")
    bench.apply("inject_fault", fault="0x3220")
    bench.run(0.01)
    assert _reading(bench) == (0.0, False, "off")
    # the terminals set meanwhile: the fault still holds the supply at 0 V
    bench.apply("field_supply", volts=24.0)
    bench.run(0.01)
    assert _reading(bench) == (0.0, False, "off")
    bench.apply("clear_fault", fault="0x3220")
    bench.run(0.01)
    assert _reading(bench) == (24.0, True, "on")


def test_injected_field_supply_fault_on_an_expansion_leaves_the_base_reading() -> None:
    """0x3220 on an expansion is that module's own supply: the base's terminals keep theirs,
    and so does its +24V LED (docs/trscat.md, §4 / §8.4 reading)."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", module=1, fault="0x3220")
    bench.run(0.01)
    assert _reading(bench) == (24.0, True, "on")
