"""Which outputs a module holds off against the PLC's output image, and why: the module
snapshot's "held_off" (docs/cpx-e-ec.md choice 40).

The Slave tab showed the output image alone (0x7002, the RxPDO): after a short on output 3
of the 8DO it still read 00010000, and a trainee took output 3 for on while the module had
switched it off (seed 002 §2.5.2 CPX error 2 "short circuit/overload", Text-ID 0x3702).
"""

from __future__ import annotations

from typing import Any

from cpx_bench import Bench

MODULES = ("16DI", "8DO", ("4AO-U-I", {"ranges": ["0-10V", "0-10V", "4-20mA", "0-20mA"]}))


def module(bench: Bench, number: int) -> dict[str, Any]:
    return bench.cpx.snapshot()["modules"][number - 1]


def test_a_shorted_output_the_plc_switches_on_is_held_off_by_the_short() -> None:
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("write_object", index=0x7002, sub=4, value=1)  # the PLC: output 3 on
    bench.run(0.01)
    assert module(bench, 2)["held_off"] == []
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.run(0.01)
    dout = module(bench, 2)
    assert dout["outputs"][3] == 1  # the PLC's image still says on
    assert dout["held_off"] == [{"channel": 3, "cause": "short_circuit_outputs"}]
    bench.apply("short_circuit", module=2, channel=3, on=False)
    bench.run(0.01)
    assert module(bench, 2)["held_off"] == []


def test_an_output_the_plc_keeps_off_is_not_held_off() -> None:
    """A short on an output switched off draws no current: nothing is held against the PLC."""
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.run(0.01)
    assert module(bench, 2)["held_off"] == []


def test_undiagnosed_hold_off_has_no_cause() -> None:
    """0x2400:3 Monitor SCO off: the module still switches the shorted output off (it is
    physics), but the bus module reports nothing, so no cause is named."""
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("write_object", index=0x2400, sub=3, value=0)
    bench.apply("write_object", index=0x7002, sub=4, value=1)
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.run(0.01)
    assert module(bench, 2)["held_off"] == [{"channel": 3}]


def test_u_out_too_low_holds_every_output_the_plc_drives() -> None:
    bench = Bench(MODULES, seed=3).to_op()
    bench.apply("write_object", index=0x7002, sub=2, value=1)  # output 1 on
    bench.apply("supply", out=16.0)
    bench.run(0.5)
    assert module(bench, 2)["held_off"] == [{"channel": 1, "cause": "undervoltage_out"}]
