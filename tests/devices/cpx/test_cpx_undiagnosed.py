"""What a module has wired but the bus module does not diagnose, and why: the model says it
(a module snapshot's "undiagnosed"), the dashboard only words it (docs/cpx-e-ec.md choice 30;
seed 002 Tab. 21-23 the causes, Tab. 27 0x2400:2 / :3 the monitoring switches).

Before, the line view compared the wiring with "diagnosed" itself and guessed the reason from
the module's type name ("DO" in it: "output off", else "current range")."""

from __future__ import annotations

from typing import Any

from cpx_bench import Bench

from devices.cpx.unseen import UNSEEN_REASONS

MODULES = ("16DI", "8DO", ("4AI-U-I", {"ranges": ["0-10V", "4-20mA", "0-20mA", "-10-+10V"]}),
           ("4AO-U-I", {"ranges": ["0-10V", "0-10V", "4-20mA", "0-20mA"]}))


def unseen(bench: Bench, module: int) -> list[dict[str, Any]]:
    return bench.cpx.snapshot()["modules"][module - 1]["undiagnosed"]


def short(channels: list[int], reason: str) -> dict[str, Any]:
    return {"cause": "short_circuit_outputs", "channels": channels, "reason": reason}


def test_a_short_on_an_output_switched_off_is_not_diagnosed_output_off() -> None:
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.run(0.01)
    assert unseen(bench, 2) == [short([3], "output_off")]
    bench.apply("write_object", index=0x7002, sub=4, value=1)  # the PLC switches output 3 on
    bench.run(0.01)
    assert unseen(bench, 2) == []  # diagnosed now (0x3702)
    assert [u for m in bench.cpx.snapshot()["modules"] for u in m["undiagnosed"]] == []


def test_monitoring_off_in_0x2400_hides_the_output_short() -> None:
    """Tab. 27 0x2400:3 Monitor SCO off: the output short drawing current is not reported;
    the one on an output switched off would not be seen anyway (its physical reason first)."""
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("write_object", index=0x2400, sub=3, value=0)
    bench.apply("short_circuit", module=2, channel=1, on=True)
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.apply("write_object", index=0x7002, sub=2, value=1)  # output 1 on, 3 off
    bench.run(0.01)
    assert bench.cpx.snapshot()["modules"][1]["diagnosed"] == []
    assert unseen(bench, 2) == [short([3], "output_off"), short([1], "monitor_off")]


def test_sensor_supply_short_with_0x2400_2_off() -> None:
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("write_object", index=0x2400, sub=2, value=0)
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    assert unseen(bench, 1) == [{"cause": "short_circuit_sensor_supply", "channels": [],
                                 "reason": "monitor_off"}]


def test_analog_channels_by_their_signal_range() -> None:
    """Choice 30: a short on an analog output bites in a voltage range only; a wire break is
    seen on a 4-20 mA input and on a current output only."""
    bench = Bench(MODULES, seed=3).to_op()
    for channel in range(4):
        bench.apply("wire_break", module=3, channel=channel, on=True)
        bench.apply("wire_break", module=4, channel=channel, on=True)
    bench.apply("short_circuit", module=4, channel=0, on=True)
    bench.apply("short_circuit", module=4, channel=2, on=True)
    bench.run(0.01)
    assert [(d["cause"], d["channel"]) for d in
            bench.cpx.snapshot()["modules"][3]["diagnosed"]] == [
        ("short_circuit_outputs", 0), ("wire_break", 2), ("wire_break", 3)]
    assert unseen(bench, 3) == [{"cause": "wire_break", "channels": [0, 2, 3],
                                 "reason": "signal_range"}]
    assert unseen(bench, 4) == [short([2], "current_range"),
                                {"cause": "wire_break", "channels": [0, 1],
                                 "reason": "signal_range"}]


def test_a_failed_module_reports_its_failure_only() -> None:
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.apply("inject_fault", module=1, fault="module_failure")
    bench.run(0.01)
    assert [d["cause"] for d in bench.cpx.snapshot()["modules"][0]["diagnosed"]] == [
        "module_failure"]
    assert unseen(bench, 1) == [{"cause": "short_circuit_sensor_supply", "channels": [],
                                 "reason": "module_failed"}]


def test_no_application_no_diagnosis() -> None:
    """Tab. 12 red on: the application controller does not answer, nothing is diagnosed."""
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("inject_fault", fault="ac_failure")
    bench.apply("short_circuit", module=1, on=True)
    bench.apply("inject_fault", module=3, fault="module_failure")
    bench.run(0.01)
    assert unseen(bench, 1) == [{"cause": "short_circuit_sensor_supply", "channels": [],
                                 "reason": "no_application"}]
    assert unseen(bench, 3) == [{"cause": "module_failure", "channels": [],
                                 "reason": "no_application"}]


def test_wired_since_the_last_diagnosis_is_pending() -> None:
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("write_object", index=0x7002, sub=4, value=1)
    bench.run(0.01)
    bench.apply("short_circuit", module=2, channel=3, on=True)
    assert unseen(bench, 2) == [short([3], "pending")]  # the next step diagnoses it
    bench.step()
    assert unseen(bench, 2) == []


def test_every_reason_the_model_gives_is_documented_data() -> None:
    assert set(UNSEEN_REASONS) == {"output_off", "current_range", "no_load_supply",
                                   "signal_range", "module_failed", "monitor_off",
                                   "no_application", "pending"}
    assert all(UNSEEN_REASONS.values())
