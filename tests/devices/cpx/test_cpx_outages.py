"""What the CPX-E-EC diagnoses while a supply or its application controller is missing
(docs/cpx-e-ec.md choices 25 and 30; seed 002 Tab. 12 red on, Tab. 20-26, Tab. 29).

Before, an output short stayed diagnosed (0x3702 besides 0x3708) with U_OUT missing, though an
output without its load supply drives no current into the short; and the errors diagnosed
before an application controller failure stayed active through it, so a cause removed
meanwhile still showed as diagnosed until the fault was cleared."""

from __future__ import annotations

from typing import Any

from cpx_bench import STI, Bench

from devices.cpx.codes import CPX_TEXT_ID_BASE, DiagType

SHORT, UNDERVOLTAGE = CPX_TEXT_ID_BASE + 2, CPX_TEXT_ID_BASE + 8  # 0x3702, 0x3708
NO_ERROR = CPX_TEXT_ID_BASE  # the information message of an error going (choice 20)


def diagnosed(bench: Bench, module: int) -> list[tuple[str, int | None]]:
    return [(d["cause"], d["channel"])
            for d in bench.cpx.snapshot()["modules"][module - 1]["diagnosed"]]


def unseen(bench: Bench, module: int) -> list[dict[str, Any]]:
    return bench.cpx.snapshot()["modules"][module - 1]["undiagnosed"]


def alarms(bench: Bench, since: int) -> list[tuple[str, bool, int]]:
    return [(r["code"], r["active"], r["module"]) for r in bench.records("alarm", since)]


def messages(bench: Bench, since: int = 0) -> list[tuple[DiagType, int, int]]:
    """The 0x10F3 messages of CPX errors from the ``since``-th message on: type, Text-ID,
    module (parameter 1); the EtherCAT side's (Tab. 17) are left out."""
    return [(m.dtype, m.text_id, m.params[0][1])
            for _sub, m in bench.cpx.history.ordered()[since:]
            if CPX_TEXT_ID_BASE <= m.text_id <= CPX_TEXT_ID_BASE + 0xFF]


def shorted_output() -> Bench:
    """16DI + 8DO in OP, I/O diagnostic interface, emergencies on; output 3 of the 8DO on
    and shorted: diagnosed."""
    bench = Bench(["16DI", "8DO"], history_flags=0x0001, **STI).to_op()
    bench.apply("write_object", index=0x7002, sub=4, value=1)
    bench.apply("short_circuit", module=2, channel=3, on=True)
    bench.run(0.01)
    assert diagnosed(bench, 2) == [("short_circuit_outputs", 3)]
    return bench


def test_without_u_out_a_short_is_not_diagnosed_the_undervoltage_is() -> None:
    """U_OUT off: the output is not energised and draws no current into its short, so the
    module reports U_OUT low only (0x3320); the short goes as any cause that goes."""
    bench = shorted_output()
    since, stored = len(bench.events), bench.cpx.history.count
    bench.apply("supply", out=0.0)
    bench.run(0.01)
    assert diagnosed(bench, 2) == [("undervoltage_out", None)]
    assert unseen(bench, 2) == [{"cause": "short_circuit_outputs", "channels": [3],
                                 "reason": "no_load_supply"}]
    assert alarms(bench, since) == [("0x3702", False, 2), ("0x3708", True, 2)]
    assert messages(bench, stored) == [(DiagType.INFO, NO_ERROR, 2),
                                       (DiagType.ERROR, UNDERVOLTAGE, 2)]
    assert [r["code"] for r in bench.records("emergency", since)] == ["0x3320"]
    assert bench.cpx.modules[1].driven[3] == 0


def test_the_short_is_diagnosed_again_when_u_out_returns() -> None:
    bench = shorted_output()
    bench.apply("supply", out=0.0)
    bench.run(0.01)
    since, stored = len(bench.events), bench.cpx.history.count
    bench.apply("supply", out=24.0)
    bench.run(0.01)
    assert diagnosed(bench, 2) == [("short_circuit_outputs", 3)]
    assert unseen(bench, 2) == []
    assert alarms(bench, since) == [("0x3708", False, 2), ("0x3702", True, 2)]
    assert messages(bench, stored) == [(DiagType.INFO, NO_ERROR, 2),
                                       (DiagType.ERROR, SHORT, 2)]
    assert [r["code"] for r in bench.records("emergency", since)] == ["0x2320"]


def test_an_application_controller_failure_leaves_nothing_diagnosed() -> None:
    """Tab. 12 red on: the application controller, which diagnoses, does not run. What it
    diagnosed goes with it (the alarms clear, as at a power loss), nothing is diagnosed
    meanwhile, and a cause removed during the failure is not shown as diagnosed."""
    bench = shorted_output()
    bench.apply("short_circuit", module=1, on=True)  # the 16DI's sensor supply
    bench.run(0.01)
    assert diagnosed(bench, 1) == [("short_circuit_sensor_supply", None)]
    since, stored = len(bench.events), bench.cpx.history.count
    bench.apply("inject_fault", fault="ac_failure")
    bench.run(0.01)
    snap = bench.cpx.snapshot()
    assert snap["diagnosis"]["errors"] == []
    assert [m["diagnosed"] for m in snap["modules"]] == [[], []]
    assert [m["error_led"]["pattern"] for m in snap["modules"]] == ["off", "off"]
    assert sorted(alarms(bench, since)) == [("0x3702", False, 1), ("0x3702", False, 2)]
    assert bench.cpx.history.count == stored  # no controller writes a message
    assert bench.records("emergency", since) == []
    assert unseen(bench, 1) == [{"cause": "short_circuit_sensor_supply", "channels": [],
                                 "reason": "no_application"}]
    assert unseen(bench, 2) == [{"cause": "short_circuit_outputs", "channels": [3],
                                 "reason": "output_off"}]  # no application: outputs off
    bench.apply("short_circuit", module=2, channel=3, on=False)  # removed meanwhile
    bench.run(0.01)
    assert diagnosed(bench, 2) == []


def test_recovery_restarts_and_diagnoses_what_is_still_there() -> None:
    """Clearing the failure restarts the bus module (choice 25): the RAM state starts empty
    (0x10F3, the mailbox), so the removed short has nothing to go from; what is still wired
    is found at the first diagnosis and reported as a new error, once."""
    bench = shorted_output()
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    bench.apply("inject_fault", fault="ac_failure")
    bench.run(0.01)
    bench.apply("short_circuit", module=2, channel=3, on=False)
    bench.run(0.01)
    since = len(bench.events)
    bench.apply("clear_fault", fault="ac_failure")
    bench.to_op()
    bench.run(0.01)
    assert diagnosed(bench, 1) == [("short_circuit_sensor_supply", None)]
    assert diagnosed(bench, 2) == []
    assert alarms(bench, since) == [("0x3702", True, 1)]
    assert messages(bench) == [(DiagType.ERROR, SHORT, 1)]


WIRE = CPX_TEXT_ID_BASE + 3  # 0x3703, Tab. 21 0x2330 "Load dump (обрыв провода)"


def open_current_loop() -> Bench:
    """4AI-U-I (4-20 mA) + 4AO-U-I (4-20 mA) in OP: the output's channel 2 loop open and the
    input's channel 1 wire broken, both diagnosed with U_OUT in tolerance."""
    bench = Bench([("4AI-U-I", {"ranges": "4-20mA"}), ("4AO-U-I", {"ranges": "4-20mA"})],
                  history_flags=0x0001, **STI).to_op()
    bench.apply("write_object", index=0x7002, sub=3, value=1000)
    bench.apply("wire_break", module=2, channel=2, on=True)
    bench.apply("wire_break", module=1, channel=1, on=True)
    bench.run(0.01)
    assert diagnosed(bench, 1) == [("wire_break", 1)]
    assert diagnosed(bench, 2) == [("wire_break", 2)]
    return bench


def test_without_u_out_an_open_current_output_is_not_diagnosed() -> None:
    """Choice 38: a current output without its load supply drives no current, so its
    open-load check has nothing to find; the module reports U_OUT low only (0x3320). The
    4-20 mA input's loop is fed by U_EL/SEN: its wire break stays diagnosed."""
    bench = open_current_loop()
    since, stored = len(bench.events), bench.cpx.history.count
    bench.apply("supply", out=0.0)
    bench.run(0.01)
    assert diagnosed(bench, 2) == [("undervoltage_out", None)]
    assert unseen(bench, 2) == [{"cause": "wire_break", "channels": [2],
                                 "reason": "no_load_supply"}]
    assert diagnosed(bench, 1) == [("wire_break", 1)]
    assert alarms(bench, since) == [("0x3703", False, 2), ("0x3708", True, 2)]
    assert messages(bench, stored) == [(DiagType.INFO, NO_ERROR, 2),
                                       (DiagType.ERROR, UNDERVOLTAGE, 2)]
    assert [r["code"] for r in bench.records("emergency", since)] == ["0x3320"]


def test_the_open_current_output_is_diagnosed_again_when_u_out_returns() -> None:
    bench = open_current_loop()
    bench.apply("supply", out=0.0)
    bench.run(0.01)
    since = len(bench.events)
    bench.apply("supply", out=24.0)
    bench.run(0.01)
    assert diagnosed(bench, 2) == [("wire_break", 2)]
    assert unseen(bench, 2) == []
    assert alarms(bench, since) == [("0x3708", False, 2), ("0x3703", True, 2)]
    assert [r["code"] for r in bench.records("emergency", since)] == ["0x2330"]
