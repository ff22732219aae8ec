"""The 8-byte emergency and the error / status registers (seed 002 §2.5.3, Tab. 20-26;
status bits §2.4.2)."""

from __future__ import annotations

from typing import Any

import pytest
from cpx_bench import STI, Bench, tab9

from devices.cpx.codes import (
    CAUSES,
    CPX_ERRORS,
    EMCY_CODES,
    ERROR_REGISTER_BITS,
    STATUS_BITS,
    emcy_code_for,
)
from devices.cpx.messages import emergency_frame, parse_emergency
from devices.ethercat import AlState

TAB21 = {0x0000: "No error", 0x1000: "General system error",
         0x2320: "Short circuit at the outputs", 0x2330: "Load dump (wire break)",
         0x3120: "Input voltage too low", 0x3320: "Output voltage too low",
         0x5000: "Hardware error (all errors > 128)"}


def test_tab20_byte_layout() -> None:
    """Tab. 20: code LE in bytes 0-1, 0x1001 in 2, 0x1002 in 3, module 4, CPX error 5,
    reserved 6, additional information 7."""
    frame = emergency_frame(0x2320, 0x03, 0x22, 2, 2, 0x05)
    assert frame == bytes((0x20, 0x23, 0x03, 0x22, 0x02, 0x02, 0x00, 0x05))
    assert parse_emergency(frame)["code"] == 0x2320


def test_tab21_codes() -> None:
    assert EMCY_CODES == TAB21
    with pytest.raises(ValueError, match=r"Tab\. 21"):
        emergency_frame(0xFF00, 0, 0, 0, 0, 0)


def test_tab22_tab23_bits() -> None:
    names = {mask.bit_length() - 1: name for mask, (name, _) in ERROR_REGISTER_BITS.items()}
    assert names == {0: "Generic Error", 1: "Current", 2: "Voltage", 4: "Communication Error",
                     7: "Manufacturer specific"}
    assert [STATUS_BITS[b] for b in range(8)] == [
        "Error at valve terminal", "Error at output", "Error at input",
        "Error at analog or technology module", "Undervoltage", "Short circuit/overload",
        "Wire break", "Other error"]


def test_errors_above_128_are_hardware_errors() -> None:
    """Tab. 21: 0x5000 for every CPX error number > 128."""
    for cause in CAUSES.values():
        assert (emcy_code_for(cause) == 0x5000) == (cause.cpx_error > 128)
    assert CPX_ERRORS[2].text == "Short circuit/overload"  # Tab. 16


# (name, modules, actions to cause it, expected emergency fields)
CASES: list[tuple[str, list[Any], list[tuple[str, int | None, dict[str, Any]]],
                  dict[str, int]]] = [
    ("output short circuit (KZA)", ["8DO"],
     [("write_object", None, {"index": 0x7001, "sub": 4, "value": 1}),
      ("short_circuit", 1, {"channel": 3, "on": True})],
     {"code": 0x2320, "register": 0x03, "status_bits": 0x22, "module": 1, "cpx_error": 2,
      "info": 3}),
    ("sensor supply short circuit (KZS)", ["16DI"],
     [("short_circuit", 1, {"on": True})],
     {"code": 0x2320, "register": 0x03, "status_bits": 0x24, "module": 1, "cpx_error": 2,
      "info": 0}),
    ("wire break, 4-20 mA input", [("4AI-U-I", {"ranges": "4-20mA"})],
     [("set_analog", 1, {"channel": c, "value": 12.0}) for c in range(4)]
     + [("wire_break", 1, {"channel": 1, "on": True})],
     {"code": 0x2330, "register": 0x81, "status_bits": 0x48, "module": 1, "cpx_error": 3,
      "info": 1}),
    ("analog output short circuit, voltage range", ["4AO-U-I"],
     [("short_circuit", 1, {"channel": 2, "on": True})],
     {"code": 0x2320, "register": 0x03, "status_bits": 0x28, "module": 1, "cpx_error": 2,
      "info": 2}),
    ("U_OUT undervoltage", ["8DO"], [("supply", None, {"out": 15.0})],
     {"code": 0x3320, "register": 0x05, "status_bits": 0x12, "module": 1, "cpx_error": 8,
      "info": 0}),
    ("U_EL/SEN undervoltage", ["16DI"], [("supply", None, {"el_sen": 17.0})],
     {"code": 0x3120, "register": 0x05, "status_bits": 0x14, "module": 0, "cpx_error": 8,
      "info": 0}),
    ("module failure", ["16DI"], [("inject_fault", 1, {"fault": "module_failure"})],
     {"code": 0x5000, "register": 0x81, "status_bits": 0x84, "module": 1, "cpx_error": 129,
      "info": 0}),
]


@pytest.mark.parametrize(("name", "modules", "actions", "expected"), CASES,
                         ids=[c[0] for c in CASES])
def test_physical_cause_to_emergency(name: str, modules: list[Any],
                                     actions: list[tuple[str, int | None, dict[str, Any]]],
                                     expected: dict[str, int]) -> None:
    """Cause -> Tab. 21 code, Tab. 22 register, Tab. 23 status bits, Tab. 24-26 bytes."""
    bench = Bench(modules, history_flags=0x0001, **STI).to_op()
    for action, module, args in actions:
        bench.apply(action, module=module, **args)
    since = len(bench.events)
    bench.run(0.01)
    sent = bench.records("emergency", since)
    assert len(sent) == 1, sent
    frame = bytes.fromhex(f"{sent[0]['code'][4:6]} {sent[0]['code'][2:4]} "
                          f"{sent[0]['register'][2:]} {sent[0]['data']}")
    assert parse_emergency(frame) == expected
    assert bench.apply("read_object", index=0x1001, sub=0) == expected["register"]
    assert bench.apply("read_object", index=0x1002, sub=0) == expected["status_bits"]


def test_no_emergency_unless_enabled() -> None:
    """Tab. 19: 0x10F3:5 bit 0 = 0 (the default) sends no emergency; the history still
    stores the message."""
    bench = tab9(**STI).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    assert bench.records("emergency") == []
    assert bench.cpx.history.count >= 1
    bench.apply("write_object", index=0x10F3, sub=5, value=0x0001)
    bench.apply("short_circuit", module=1, on=False)
    bench.run(0.01)
    assert [r["code"] for r in bench.records("emergency")] == ["0x0000"]  # no error left


def test_no_error_emergency_only_when_the_last_error_goes() -> None:
    """Tab. 21 «00 00 Нет ошибок» (no errors): one of two errors going sends nothing, the
    history gets its CPX error 0 message; the last one going sends 0x0000 with 0x1001 /
    0x1002 clear (DS 301 leaves the partial "error reset" optional: choice 19)."""
    bench = Bench(["16DI", "8DO"], history_flags=0x0001, **STI).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.apply("inject_fault", module=2, fault="module_failure")
    bench.run(0.01)
    since = len(bench.events)
    bench.apply("clear_fault", module=2, fault="module_failure")
    bench.run(0.01)
    assert bench.records("emergency", since) == []
    assert bench.cpx.history.ordered()[-1][1].text_id == 0x3700
    bench.apply("short_circuit", module=1, on=False)
    bench.run(0.01)
    sent = bench.records("emergency", since)
    assert [(r["code"], r["register"], r["data"]) for r in sent] == [
        ("0x0000", "0x00", "00 00 00 00 00")]


def test_emergencies_reach_the_master() -> None:
    """8-byte frames through the mailbox: taken by the master from PREOP on."""
    bench = Bench(["8DO"], master=False, history_flags=0x0001, **STI)
    bench.apply("supply", out=12.0)
    bench.run(0.01)
    assert bench.cpx.take_emergencies() == []  # INIT: the mailbox does not run
    bench.cpx.request_state(AlState.PREOP)
    frames = bench.cpx.take_emergencies()
    assert [len(f) for f in frames] == [8]
    assert frames[0][:2] == bytes((0x20, 0x33))  # 0x3320
    assert bench.cpx.take_emergencies() == []


def unread_emergency() -> Bench:
    """An undervoltage at U_OUT (0x3320) in PREOP with the cable out: queued, unread."""
    bench = Bench(["8DO"], master=False, history_flags=0x0001, **STI)
    bench.run(0.01)
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.al_state is AlState.PREOP
    bench.cpx.set_link(False)
    bench.apply("supply", out=12.0)
    bench.run(0.01)
    assert [r["code"] for r in bench.records("emergency")] == ["0x3320"]
    assert bench.cpx.take_emergencies() == []
    bench.cpx.set_link(True)
    return bench


def test_unread_emergencies_are_lost_through_init() -> None:
    """The mailbox stops on the way to INIT and its queue goes (ETG.1000.6, SSC
    MBX_StopMailboxHandler); the 0x10F3 history is an object and keeps the message."""
    bench = unread_emergency()
    stored = bench.cpx.history.count
    bench.cpx.request_state(AlState.INIT)
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.al_state is AlState.PREOP
    assert bench.cpx.take_emergencies() == []
    assert bench.cpx.history.count == stored >= 1


def test_unread_emergencies_wait_without_init() -> None:
    bench = unread_emergency()
    assert [f[:2] for f in bench.cpx.take_emergencies()] == [bytes((0x20, 0x33))]


def test_the_mailbox_keeps_the_newest_16_before_preop() -> None:
    """In INIT since power-up the mailbox does not run: the emergencies wait for PREOP, the
    newest 16 of them (docs/cpx-e-ec.md choice 34, MAILBOX_DEPTH; the seed gives no depth)."""
    bench = Bench(["16DI"], master=False, history_flags=0x0001, **STI)
    # 21 emergencies: the sensor-supply short and its "no error" ten times, then the short
    for on in [True, False] * 10 + [True]:
        bench.apply("short_circuit", module=1, on=on)
        bench.run(0.002)
    assert bench.cpx.al_state is AlState.INIT and len(bench.records("emergency")) == 21
    bench.cpx.request_state(AlState.PREOP)
    codes = [parse_emergency(f)["code"] for f in bench.cpx.take_emergencies()]
    assert codes == [0x0000, 0x2320] * 8  # the last 16: the first five went


def test_status_bits_as_inputs() -> None:
    """§2.4.2: with status bits on, the 8 bits are the bus module's inputs I0 ... I7; the
    CPX system's example "short circuit at the output" sets bits 5 and 1."""
    bench = tab9().to_op()
    assert bench.cpx.bus.in_values == [0] * 8
    bench.apply("write_object", index=0x7003, sub=1, value=1)
    bench.apply("short_circuit", module=3, channel=0, on=True)
    bench.run(0.01)
    assert bench.cpx.bus.in_values == [0, 1, 0, 0, 0, 1, 0, 0]
    assert [bench.apply("read_object", index=0x6000, sub=s) for s in range(1, 9)] == \
        [0, 1, 0, 0, 0, 1, 0, 0]


def test_short_is_seen_only_with_the_output_on_and_monitored() -> None:
    """KZA is detected while the output draws current; 0x2400:3 Monitor SCO off hides it,
    the output is switched off all the same."""
    bench = tab9().to_op()
    bench.apply("short_circuit", module=2, channel=0, on=True)
    bench.run(0.01)
    assert bench.cpx.diagnosis.active == []
    bench.apply("write_object", index=0x7002, sub=1, value=1)
    bench.run(0.01)
    assert [e.fault.cause for e in bench.cpx.diagnosis.active] == ["short_circuit_outputs"]
    assert bench.cpx.modules[1].driven[0] == 0
    bench.apply("write_object", index=0x2400, sub=3, value=0)
    bench.run(0.01)
    assert bench.cpx.diagnosis.active == []
    assert bench.cpx.modules[1].driven[0] == 0
