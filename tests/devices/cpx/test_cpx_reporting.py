"""Which DIL mode sends the CPX-E system's error messages to the PLC (seed 002 §2.5, the note
before §2.5.1: "Чтобы убедиться, что сообщения об ошибках системы CPX-E автоматически
отображаются в управляющем ПО, интерфейс диагностики входов/выходов должен быть
активирован"; docs/cpx-e-ec.md choice 33)."""

from __future__ import annotations

import pytest
from cpx_bench import Bench

from devices.cpx.codes import CPX_TEXT_ID_BASE

# (DIL 1, DIL 2) of Tab. 6 -> are the CPX error messages reported?
MODES = [((False, False), False), ((False, True), False), ((True, False), True)]
IDS = ["no diagnosis", "status bits", "I/O diagnostic interface"]
SHORT = CPX_TEXT_ID_BASE + 2  # Text-ID 0x3702, CPX error 2


def shorted(dil1: bool, dil2: bool) -> tuple[Bench, int]:
    """16DI + 8DO in OP with emergencies on, output 0 of the 8DO switched on and shorted."""
    bench = Bench(["16DI", "8DO"], dil1=dil1, dil2=dil2, history_flags=0x0001).to_op()
    since = len(bench.events)
    bench.apply("write_object", index=0x7002, sub=1, value=1)
    bench.apply("short_circuit", module=2, channel=0, on=True)
    bench.run(0.01)
    return bench, since


def text_ids(bench: Bench) -> list[int]:
    return [int(m["text_id"], 16) for m in bench.cpx.history.snapshot()["messages"]]


@pytest.mark.parametrize(("dil", "reported"), MODES, ids=IDS)
def test_error_messages_only_with_the_io_diagnostic_interface(
        dil: tuple[bool, bool], reported: bool) -> None:
    """An error coming: the 0x10F3 error message and its emergency only in STI mode; the
    registers, the alarm event and the SF LED in every mode."""
    bench, since = shorted(*dil)
    assert (SHORT in text_ids(bench)) is reported
    codes = [r["code"] for r in bench.records("emergency", since)]
    assert codes == (["0x2320"] if reported else [])
    assert bool(bench.records("coe_emergency", since)) is reported
    assert bench.apply("read_object", index=0x1001, sub=0) == 0x03
    assert bench.apply("read_object", index=0x1002, sub=0) == 0x22
    assert [r["active"] for r in bench.records("alarm", since)] == [True]
    assert bench.led("SF") != "off"


@pytest.mark.parametrize(("dil", "reported"), MODES, ids=IDS)
def test_error_going_only_with_the_io_diagnostic_interface(
        dil: tuple[bool, bool], reported: bool) -> None:
    """An error going: the CPX error 0 information message and the "no error" emergency
    0x0000 (Tab. 21) only in STI mode."""
    bench, _ = shorted(*dil)
    before = len(bench.cpx.history.snapshot()["messages"])
    since = len(bench.events)
    bench.apply("short_circuit", module=2, channel=0, on=False)
    bench.run(0.01)
    gone = text_ids(bench)[before:]
    assert gone == ([CPX_TEXT_ID_BASE] if reported else [])
    assert [r["code"] for r in bench.records("emergency", since)] == \
        (["0x0000"] if reported else [])
    assert [r["active"] for r in bench.records("alarm", since)] == [False]


@pytest.mark.parametrize(("dil", "reported"), MODES, ids=IDS)
def test_ethercat_messages_in_every_mode(dil: tuple[bool, bool], reported: bool) -> None:
    """Tab. 17's EtherCAT-side messages are not CPX error messages: the 0xF030 warning 0x3801
    of every start is stored whatever the DIL switches say."""
    bench = Bench(["16DI", "8DO"], dil1=dil[0], dil2=dil[1]).to_op()
    assert 0x3801 in text_ids(bench)


def test_restart_into_sti_reports_what_is_still_there() -> None:
    """The mode changes only at a restart, which empties the RAM state (§2.1.7): an error
    unreported before it is reported as a new one after it, once; nothing "goes" at the
    restart itself."""
    bench = Bench(["16DI"], history_flags=0x0001).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    assert SHORT not in text_ids(bench) and bench.records("emergency") == []
    bench.apply("set_dil", dil1=True, dil2=False)
    bench.run(0.01)
    assert SHORT not in text_ids(bench)  # not active before the restart
    since = len(bench.events)
    bench.apply("restart")
    bench.to_op()
    bench.run(0.01)
    assert text_ids(bench).count(SHORT) == 1
    assert CPX_TEXT_ID_BASE not in text_ids(bench)
    # Reported at the start, before the master's PS write of 0x10F3:5 (Tab. 14: 0x0000 from
    # power-up until then): in the history, no emergency (docs/cpx-e-ec.md choice 19).
    assert bench.records("emergency", since) == []
    assert bench.cpx.od.peek(0x10F3, 5) == 0x0001
