"""The CPX-E I/O modules behind the bus module: signals, scaling and the faults they see
(seed 002 §2.3.2 modules, §2.1.4 the 1CI, §2.5.3 fault kinds; scaling in docs/cpx-e-ec.md)."""

from __future__ import annotations

import pytest
from cpx_bench import Bench

from devices.cpx.catalog import module_type
from devices.cpx.modules import ANALOG_RANGES, FULL_SCALE, CpxModule, Monitors


def module(name: str, **options: object) -> CpxModule:
    return CpxModule.build(1, module_type(name), options)


@pytest.mark.parametrize(("range_name", "value", "raw"), [
    ("0-10V", 0.0, 0), ("0-10V", 5.0, 16384), ("0-10V", 10.0, FULL_SCALE),
    ("-10-+10V", -10.0, -FULL_SCALE), ("-10-+10V", 2.5, 8192),
    ("0-20mA", 20.0, FULL_SCALE), ("4-20mA", 4.0, 0), ("4-20mA", 12.0, 16384),
])
def test_analog_input_scaling(range_name: str, value: float, raw: int) -> None:
    m = module("4AI-U-I", ranges=range_name)
    m.analog_in[2] = value
    m.sample_inputs()
    assert m.in_values[2] == pytest.approx(raw, abs=1)


@pytest.mark.parametrize("range_name", [r.name for r in ANALOG_RANGES.values()])
def test_wire_break_is_diagnosed_in_4_20_ma_only(range_name: str) -> None:
    m = module("4AI-U-I", ranges=range_name)
    m.wire_broken.add(1)
    causes = [(f.cause, f.channel) for f in m.faults(Monitors(), supply_ok=True)]
    assert causes == ([("wire_break", 1)] if range_name == "4-20mA" else [])
    m.sample_inputs()
    assert m.in_values[1] == (-FULL_SCALE // 4 if range_name == "4-20mA" else 0)


def test_analog_output_faults_by_range() -> None:
    """An open current loop is a wire break; a short on a voltage output is a short."""
    m = module("4AO-U-I", ranges=["0-10V", "0-10V", "4-20mA", "4-20mA"])
    m.shorted.update({0, 2})
    m.wire_broken.update({1, 3})
    m.drive_outputs([1000, 1000, 1000, 1000], supply_ok=True)
    causes = [(f.cause, f.channel, f.output) for f in m.faults(Monitors(), supply_ok=True)]
    assert causes == [("short_circuit_outputs", 0, True), ("wire_break", 3, True)]
    assert m.energised == [False, True, True, True]
    assert m.output_value(2) == pytest.approx(4.0 + 1000 / FULL_SCALE * 16.0)


def test_u_out_missing_switches_the_outputs_off() -> None:
    m = module("8DO")
    m.drive_outputs([1] * 8, supply_ok=False)
    assert m.driven == [0] * 8
    assert [f.cause for f in m.faults(Monitors(), supply_ok=False)] == ["undervoltage_out"]
    assert m.faults(Monitors(v_out=False), supply_ok=False) == []


def test_a_short_without_u_out_draws_no_current() -> None:
    """An output commanded on without its load supply is not energised: its short is not
    seen (digital or voltage output), only U_OUT low (docs/cpx-e-ec.md choice 30)."""
    for name, values in (("8DO", [1] * 8), ("4AO-U-I", [1000] * 4)):
        m = module(name)
        m.shorted.add(2)
        m.drive_outputs(values, supply_ok=False)
        assert [f.cause for f in m.faults(Monitors(), supply_ok=False)] == ["undervoltage_out"]
        m.drive_outputs(values, supply_ok=True)
        assert [(f.cause, f.channel) for f in m.faults(Monitors(), supply_ok=True)] == [
            ("short_circuit_outputs", 2)]


def test_an_open_current_output_without_u_out_is_not_seen() -> None:
    """No load supply, no loop current: the open-load check of a current output finds
    nothing, only U_OUT low (docs/cpx-e-ec.md choice 38)."""
    m = module("4AO-U-I", ranges="4-20mA")
    m.wire_broken.add(1)
    m.drive_outputs([1000] * 4, supply_ok=False)
    assert [f.cause for f in m.faults(Monitors(), supply_ok=False)] == ["undervoltage_out"]
    m.drive_outputs([1000] * 4, supply_ok=True)
    assert [(f.cause, f.channel) for f in m.faults(Monitors(), supply_ok=True)] == [
        ("wire_break", 1)]


def test_counter_counts_resets_and_latches() -> None:
    """CPX-E-1CI: control bit 0 sets the counter to 0, bit 1 latches it (FieldRig layout)."""
    m = module("1CI")
    m.count_rate_hz = 1000.0
    m.step(250_000)
    m.sample_inputs()
    assert m.in_values[:3] == [250, 0, 1000]
    m.drive_outputs([0x0002], supply_ok=True)
    m.step(100_000)
    m.sample_inputs()
    assert m.in_values[:2] == [350, 250]
    m.drive_outputs([0x0001], supply_ok=True)
    m.sample_inputs()
    assert m.in_values[0] == 0
    m.wire_broken.add(0)
    m.step(100_000)
    m.sample_inputs()
    assert m.in_values[0] == 0 and m.in_values[3] == 0
    assert [f.cause for f in m.faults(Monitors(), True)] == ["wire_break"]


def test_sensor_supply_short_blanks_the_inputs() -> None:
    m = module("16DI")
    m.field_inputs[:] = [True] * 16
    m.sensor_supply_short = True
    m.sample_inputs()
    assert m.in_values == [0] * 16
    assert m.faults(Monitors(scs=False), True) == []


def test_forced_input_wins_over_the_field() -> None:
    bench = Bench(["16DI"], seed=3).to_op()
    bench.apply("set_input", module=1, channel=0, on=True)
    bench.apply("force", module=1, channel=0, value=0)
    bench.apply("force", module=1, channel=1, value=1)
    bench.step()
    assert bench.cpx.modules[0].in_values[:2] == [0, 1]


def test_rig_options() -> None:
    m = CpxModule.build(1, module_type("4AI-U-I"),
                        {"ranges": ["0-10V", "4-20mA", "0-20mA", "-10-+10V"]})
    assert [m.channel_range(c).name for c in range(4)] == [
        "0-10V", "4-20mA", "0-20mA", "-10-+10V"]
    assert m.analog_in == [0.0, 4.0, 0.0, 0.0]  # sensors at rest: no wire break
    with pytest.raises(ValueError, match="4 channels"):
        CpxModule.build(1, module_type("4AI-U-I"), {"ranges": ["0-10V"]})


def test_snapshot_says_which_wired_faults_the_module_diagnoses() -> None:
    """docs/cpx-e-ec.md choice 30: an output short counts only while the output is switched
    on. The review: the dashboard lit the 8DO's red LED from the wiring ("shorted") while the
    device diagnosed nothing; each module's snapshot now carries what the bus module
    diagnoses on it ("diagnosed") and what is wired but not diagnosed, and why
    ("undiagnosed": the short draws no current while the output is off)."""
    bench = Bench(["16DI", "8DO"], seed=3).to_op()
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.run(0.01)
    module = bench.cpx.snapshot()["modules"][1]
    assert module["shorted"] == [3]
    assert module["diagnosed"] == [] and module["undiagnosed"] == [
        {"cause": "short_circuit_outputs", "channels": [3], "reason": "output_off"}]
    assert bench.cpx.snapshot()["diagnosis"]["error_register"] == 0
    bench.apply("write_object", index=0x7002, sub=4, value=1)  # the PLC switches output 3 on
    bench.run(0.01)
    module = bench.cpx.snapshot()["modules"][1]
    assert module["diagnosed"] == [{"cause": "short_circuit_outputs", "channel": 3}]
    assert module["undiagnosed"] == []
    assert bench.cpx.snapshot()["modules"][0]["diagnosed"] == []
