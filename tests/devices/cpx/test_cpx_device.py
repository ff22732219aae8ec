"""The CPX-E-EC on the built-in master: ESM, process data, supervision, sync managers
(seed 002 §2.4.1 Tab. 11-12, §2.5.2 Tab. 17; ETG.1000.6 via devices/ethercat.py)."""

from __future__ import annotations

import json
import random

import pytest
from cpx_bench import STEP_US, STI, TAB9_MODULES, Bench, tab9

from devices.cpx.codes import TEXT_BUS_CYCLE, TEXT_SM_ADDRESS, TEXT_SM_SETTINGS, TEXT_SM_SIZE
from devices.cpx.device import CpxEEc
from devices.device import CommandError
from devices.ethercat import AlState
from devices.od import AbortCode, DataType, SdoAbort


def test_master_brings_it_to_op() -> None:
    bench = tab9().to_op()
    states = [(r["from"], r["to"]) for r in bench.records("state")]
    assert states == [("INIT", "PREOP"), ("PREOP", "SAFEOP"), ("SAFEOP", "OP")]
    assert bench.cpx.station_address == 1001  # the master numbers its slaves
    assert bench.cpx.al_status == 0x08 and bench.cpx.al_status_code == 0


def test_snapshot_is_plain_json() -> None:
    snap = tab9().to_op().cpx.snapshot()
    for key in ("kind", "id", "powered", "esm", "al_status", "al_status_code", "leds"):
        assert key in snap
    assert snap["kind"] == "cpx_e_ec" and snap["esm"] == "OP"
    json.dumps(snap)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"modules": ["CPX-E-99X"]}, "module 1: unknown CPX-E module"),
    ({"modules": [("4AI-U-I", {"ranges": "0-5mA"})]}, "unknown signal range"),
    ({"modules": [("8DO", {"ranges": "0-10V"})]}, "no signal ranges"),
    ({"modules": [("16DI", {"debounce": 3})]}, "unknown option"),
    ({"modules": ["8DO"] * 11}, "at most 10"),
    ({"rotary_switch": 4096}, "0 ... 4095"),
])
def test_bad_configuration(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        CpxEEc("cpx", random.Random(0), **kwargs)


def test_outputs_follow_the_plc_in_op_only() -> None:
    """Tab. 11: in SAFEOP only the inputs are updated; the outputs do not keep their state
    (0x2400:7 = 0, the default). 1 holds the last state, 2 takes 0x21xx."""
    bench = tab9(master=False)
    for target in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
        bench.cpx.request_state(target)
    bench.apply("write_object", index=0x7002, sub=2, value=1)
    bench.apply("write_object", index=0x7005, sub=1, value=16384)
    bench.step()
    dout, aout = bench.cpx.modules[1], bench.cpx.modules[4]
    assert dout.driven[1] == 1 and aout.output_value(0) == pytest.approx(5.0, abs=1e-3)
    bench.cpx.request_state(AlState.SAFEOP)
    bench.step()
    assert dout.driven[1] == 0 and aout.driven[0] == 0
    bench.apply("write_object", index=0x2400, sub=7, value=1)
    bench.step()
    assert dout.driven[1] == 1
    bench.apply("write_object", index=0x2102, sub=1, value=1)
    bench.apply("write_object", index=0x2400, sub=7, value=2)
    bench.step()
    assert (dout.driven[0], dout.driven[1]) == (1, 0)


@pytest.mark.parametrize(("request_", "code"), (("boot", 0x0011), ("unknown", 0x0012)))
def test_a_request_refused_in_op_drops_to_safeop_with_outputs_off(request_: str,
                                                                    code: int) -> None:
    """ETG.1000.6 (SSC AL_ControlInd, SOES ESC_state): a request refused in OP (OP -> BOOT is
    no transition, Tab. 11's BOOT is reached from INIT: 0x0011; an unknown state: 0x0012)
    leaves the bus module in SAFEOP + error, the outputs as Tab. 11 has them there (0x2400:7
    = 0: off); Error blinking red (Tab. 12 invalid configuration)."""
    bench = tab9(master=False)
    for target in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
        bench.cpx.request_state(target)
    bench.apply("write_object", index=0x7002, sub=2, value=1)
    bench.step()
    dout = bench.cpx.modules[1]
    assert dout.driven[1] == 1
    if request_ == "boot":
        bench.cpx.request_state(AlState.BOOT)
    else:  # AL control 0x05, as the wire face hands it to the ESM
        bench.cpx.esm.request_unknown(0x05, False, bench.cpx.now_us)
    bench.step()
    cpx = bench.cpx
    assert (cpx.al_state, cpx.al_status, cpx.al_status_code) == (AlState.SAFEOP, 0x14, code)
    assert dout.driven[1] == 0
    assert bench.led_state("Error") == ("blinking", "red")


def test_inputs_are_sampled_from_safeop_on() -> None:
    bench = tab9(master=False)
    bench.apply("set_input", module=1, channel=3, on=True)
    bench.cpx.request_state(AlState.PREOP)
    bench.step()
    assert bench.apply("read_object", index=0x6001, sub=4) == 0
    bench.cpx.request_state(AlState.SAFEOP)
    bench.step()
    assert bench.apply("read_object", index=0x6001, sub=4) == 1


def test_cable_pulled_and_plugged_again() -> None:
    """No link: LA IN off, Error blinking, the master loses the slave; the Sync Manager
    watchdog takes OP to SAFEOP (0x001B); plugged again, the master brings it back."""
    bench = tab9().to_op()
    bench.apply("cable", port="in", connected=False)
    bench.run(0.2)
    assert not bench.cpx.reachable()
    assert bench.cpx.al_state is AlState.SAFEOP and bench.cpx.al_status_code == 0x001B
    assert bench.led("LA IN") == "off" and bench.led_state("Error") == ("blinking", "red")
    bench.apply("cable", port="in", connected=True)
    bench.to_op()
    assert bench.led_state("Error") == ("off", "red")


def test_sync_error_until_cleared() -> None:
    bench = tab9().to_op()
    bench.apply("inject_fault", fault="sync_error")
    bench.run(2.5)  # the master's retry is refused while sync events are missed
    assert bench.cpx.al_state is AlState.SAFEOP and bench.cpx.al_status_code == 0x001A
    bench.apply("clear_fault", fault="sync_error")
    bench.to_op()


def _cycle(bench: Bench, missed: bool) -> None:
    """One master cycle whose SM event is missed (the "sync_error" fault) or arrives."""
    if missed != bench.cpx.has_fault("sync_error"):
        bench.apply("inject_fault" if missed else "clear_fault", fault="sync_error")
    bench.cpx.exchange_frame(bench.now + STEP_US)
    bench.step()


def _counter_at_limit_minus_three(bench: Bench) -> int:
    """Miss, then good cycles until one more miss (+3) brings the counter exactly to the
    limit: the counter before that miss."""
    limit = bench.apply("read_object", index=0x10F1, sub=2)
    _cycle(bench, True)
    while bench.cpx.sync_counter > limit - 3:
        _cycle(bench, False)
    assert bench.cpx.sync_counter == limit - 3
    return limit


def test_sync_error_when_the_counter_reaches_0x10f1_2() -> None:
    """Seed 002 names 0x10F1:2 (Tab. 27) and the sync error's single flash (Tab. 12), not
    the comparison: the ETG rule of the sample stack (and of the TRS-CAT) is an error once
    the counter reaches the limit. The miss before it leaves the slave in OP."""
    bench = tab9(master=False)
    for target in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
        bench.cpx.request_state(target)
    limit = _counter_at_limit_minus_three(bench)
    assert bench.cpx.al_state is AlState.OP
    _cycle(bench, True)  # the counter reaches the limit
    assert bench.cpx.sync_counter == limit
    assert bench.cpx.al_state is AlState.SAFEOP and bench.cpx.al_status_code == 0x001A


def test_op_refused_with_the_counter_at_0x10f1_2() -> None:
    bench = tab9(master=False)
    for target in (AlState.PREOP, AlState.SAFEOP):
        bench.cpx.request_state(target)
    limit = _counter_at_limit_minus_three(bench)
    _cycle(bench, True)
    assert bench.cpx.sync_counter == limit
    bench.apply("clear_fault", fault="sync_error")
    bench.cpx.request_state(AlState.OP)
    assert bench.cpx.al_state is AlState.SAFEOP and bench.cpx.al_status_code == 0x001A


def test_application_controller_failure_ignores_the_master() -> None:
    bench = tab9(master=False)
    bench.apply("inject_fault", fault="ac_failure")
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.al_state is AlState.INIT and bench.cpx.al_status == 0x01
    with pytest.raises(CommandError, match="application controller"):
        bench.apply("read_object", index=0x1000, sub=0)
    bench.apply("clear_fault", fault="ac_failure")
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.al_state is AlState.PREOP


def test_application_controller_failure_stops_the_masters_coe() -> None:
    """Tab. 12 red on: "critical communication error, the application controller does not
    answer" - the ESC keeps the AL state, but the CoE mailbox runs on the controller: the
    built-in master's SDO upload / download and its emergency fetch get no answer (choice 25).
    The operator's read_object already failed (test above); the master's path did not."""
    bench = Bench(["8DO"], master=False, history_flags=0x0001)
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.sdo_upload(0x1000, 0)  # the mailbox answers in PREOP
    bench.apply("supply", out=12.0)  # U_OUT undervoltage: an emergency waits in the mailbox
    bench.run(0.01)
    bench.apply("inject_fault", fault="ac_failure")
    assert bench.cpx.al_state is AlState.PREOP  # the AL status does not move
    with pytest.raises(SdoAbort) as upload:
        bench.cpx.sdo_upload(0x1000, 0)
    assert upload.value.code is AbortCode.SDO_TIMEOUT
    before = bench.cpx.od.peek(0x2400, 7)
    with pytest.raises(SdoAbort) as download:
        bench.cpx.sdo_download(0x2400, 7, bytes((2,)))
    assert download.value.code is AbortCode.SDO_TIMEOUT
    assert bench.cpx.od.peek(0x2400, 7) == before
    assert bench.cpx.take_emergencies() == []


# (fault, sm, refused transition, AL status code, Text-ID)
SM_CASES = [
    ("sm_invalid_address", 0, AlState.PREOP, 0x0016, TEXT_SM_ADDRESS),
    ("sm_invalid_settings", 1, AlState.PREOP, 0x0016, TEXT_SM_SETTINGS),
    ("sm_invalid_size", 2, AlState.SAFEOP, 0x001D, TEXT_SM_SIZE),
    ("sm_invalid_size", 3, AlState.SAFEOP, 0x001E, TEXT_SM_SIZE),
    # SM2 / SM3: 0x001D / 0x001E whatever is wrong (ETG sample stack, CheckSmSettings); the
    # history's Text-ID names what (Tab. 17)
    ("sm_invalid_address", 3, AlState.SAFEOP, 0x001E, TEXT_SM_ADDRESS),
    ("sm_invalid_settings", 2, AlState.SAFEOP, 0x001D, TEXT_SM_SETTINGS),
    ("sm_invalid_address", 2, AlState.SAFEOP, 0x001D, TEXT_SM_ADDRESS),
    ("sm_invalid_settings", 3, AlState.SAFEOP, 0x001E, TEXT_SM_SETTINGS),
]


@pytest.mark.parametrize(("fault", "sm", "target", "code", "text_id"), SM_CASES)
def test_sync_manager_errors(fault: str, sm: int, target: AlState, code: int,
                             text_id: int) -> None:
    """Tab. 17 0x0011-0x0013: the transition that checks the SM is refused, the history
    says which SM (parameter 1) and which value (parameter 2)."""
    bench = tab9(master=False)
    bench.apply("inject_fault", fault=fault, sm=sm)
    for step in (AlState.PREOP, AlState.SAFEOP):
        bench.cpx.request_state(step)
        if step is target:
            break
    assert bench.cpx.al_status == (int(target) >> 1 if target is AlState.SAFEOP else 1) | 0x10
    assert bench.cpx.al_status_code == code
    message = bench.cpx.history.ordered()[-1][1]
    assert message.text_id == text_id and message.params[0] == (DataType.UNSIGNED8, sm)
    assert message.params[1][0] is DataType.UNSIGNED16
    bench.apply("clear_fault", fault=fault, sm=sm)
    bench.cpx.request_state(target, ack=True)  # AL control bit 4 (ETG.1000.6)
    assert bench.cpx.al_state is target


def test_bus_cycle_warning_does_not_stop_the_transition() -> None:
    """Tab. 17 0x000F: a warning of the cycle-time measurement."""
    bench = tab9(master=False)
    bench.apply("inject_fault", fault="bus_cycle_time")
    bench.cpx.request_state(AlState.PREOP)
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_state is AlState.SAFEOP
    assert TEXT_BUS_CYCLE in [m.text_id for _s, m in bench.cpx.history.ordered()]


@pytest.mark.parametrize(("path", "code"), [
    ([AlState.OP], 0x0011), ([AlState.SAFEOP], 0x0011),
    ([AlState.PREOP, AlState.BOOT], 0x0011)])
def test_invalid_requests(path: list[AlState], code: int) -> None:
    """ETG.1000.6: INIT -> OP, INIT -> SAFEOP, PREOP -> BOOT are no transitions."""
    bench = tab9(master=False)
    for target in path:
        bench.cpx.request_state(target)
    assert bench.cpx.al_status_code == code and bench.cpx.al_status & 0x10


def test_boot_from_init_and_back() -> None:
    """Tab. 11 "Bootstrap": reached from INIT, left to INIT."""
    bench = tab9(master=False)
    bench.cpx.request_state(AlState.BOOT)
    assert bench.cpx.al_state is AlState.BOOT
    bench.cpx.request_state(AlState.INIT)
    assert bench.cpx.al_state is AlState.INIT


def test_fault_targets_are_checked() -> None:
    bench = tab9(master=False)
    with pytest.raises(CommandError, match="bus module"):
        bench.apply("inject_fault", module=1, fault="watchdog")
    with pytest.raises(CommandError, match="sm="):
        bench.apply("inject_fault", fault="sm_invalid_size")
    with pytest.raises(CommandError, match="channel"):
        bench.apply("inject_fault", module=4, fault="wire_break")
    with pytest.raises(CommandError, match="not injected"):
        bench.apply("clear_fault", fault="watchdog")
    with pytest.raises(CommandError, match="no module 9"):
        bench.apply("set_input", module=9, channel=0, on=True)
    with pytest.raises(CommandError, match="no digital inputs"):
        bench.apply("set_input", module=2, channel=0, on=True)


def test_brown_out_powers_it_down_after_20_ms() -> None:
    """Tab. 29: below the electronics' minimum for 20 ms the module stops; 17 V is only an
    undervoltage."""
    bench = tab9().to_op()
    bench.apply("supply", el_sen=17.0)
    bench.run(0.1)
    assert bench.cpx.powered
    assert [e.fault.cause for e in bench.cpx.diagnosis.active] == ["undervoltage_el_sen"]
    bench.apply("supply", el_sen=8.0)
    bench.run(0.021)
    assert not bench.cpx.powered and not bench.cpx.reachable()


def test_power_cycle_clears_the_history() -> None:
    bench = tab9(**STI).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    assert bench.cpx.history.count >= 2
    bench.apply("power", on=False)
    bench.run(0.05)
    bench.apply("power", on=True)
    assert bench.cpx.history.count == 0
    alarms = [(r["code"], r["active"]) for r in bench.records("alarm")]
    # U_EL/SEN falling is seen during the 20 ms bridging; the power loss ends every alarm
    assert alarms == [("0x3702", True), ("0x3708", True), ("0x3708", False),
                      ("0x3702", False)]


def test_io_diagnostic_interface() -> None:
    """§2.4.3: 16 output bits ask, 16 input bits answer (function numbers of the CPX-E
    system description: 1936 first faulty module, 1937 status bits, 1938 its error number,
    2008 + 4m + 1 the error number of module m)."""
    bench = Bench(TAB9_MODULES, dil1=True).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    answers = {}
    for number in (1936, 1937, 1938, 2008 + 4 * 1 + 1, 2008 + 4 * 2 + 1):
        bench.apply("write_object", index=0x7000, sub=1, value=0x8000 | number)
        bench.step()
        answers[number] = bench.apply("read_object", index=0x6000, sub=1)
    assert answers == {1936: 0x8001, 1937: 0x8024, 1938: 0x8002, 2013: 0x8002, 2017: 0x8000}
    bench.apply("write_object", index=0x7000, sub=1, value=1937)  # no read request
    bench.step()
    assert bench.apply("read_object", index=0x6000, sub=1) == 0


def test_io_diagnostic_interface_takes_its_request_in_op_only() -> None:
    """Tab. 11: in SAFEOP only the inputs are updated; the output word that asks (§2.4.3) is
    an output like the others, not taken before OP. The answer (an input) keeps following the
    request taken last in OP; a request written in SAFEOP is taken at the first OP cycle."""
    bench = Bench(TAB9_MODULES, master=False, dil1=True)
    for target in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
        bench.cpx.request_state(target)
    bench.apply("short_circuit", module=1, on=True)
    bench.apply("write_object", index=0x7000, sub=1, value=0x8000 | 1936)
    bench.run(0.01)
    assert bench.apply("read_object", index=0x6000, sub=1) == 0x8001
    bench.cpx.request_state(AlState.SAFEOP)
    bench.apply("write_object", index=0x7000, sub=1, value=0x8000 | 1938)
    bench.run(0.005)
    assert bench.apply("read_object", index=0x6000, sub=1) == 0x8001  # still 1936's answer
    bench.cpx.request_state(AlState.OP)
    bench.step()
    assert bench.apply("read_object", index=0x6000, sub=1) == 0x8002  # 1938: error number


def test_outputs_die_with_the_application() -> None:
    """No power or no application controller: nothing drives the outputs."""
    bench = tab9().to_op()
    bench.apply("write_object", index=0x7002, sub=1, value=1)
    bench.step()
    dout = bench.cpx.modules[1]
    assert dout.driven[0] == 1 and dout.energised[0]
    bench.apply("inject_fault", fault="ac_failure")
    bench.step()
    assert dout.driven[0] == 0 and not dout.energised[0]
    bench.apply("clear_fault", fault="ac_failure")
    bench.apply("power", on=False)
    bench.run(0.03)
    assert dout.driven == [0] * 8 and not any(dout.energised)
