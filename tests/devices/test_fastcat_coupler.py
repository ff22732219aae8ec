"""The FastCAT coupler model: construction, ESM, object dictionary, alarms, physical causes,
LEDs (seed 000 §2, §5, §6.1-§6.5, §6.16-§6.23, §6.31, §7)."""

from __future__ import annotations

import random

import pytest
from fastcat_bench import THREE, Bench, scan_us

from devices.device import CommandError
from devices.ethercat import ALLOWED_TRANSITIONS, AlState
from devices.fastcat.alarms import COUPLER_CODES, MODULE_CODES, AlarmCode
from devices.fastcat.catalog import CATALOG
from devices.fastcat.coupler import FastCat
from devices.od import AbortCode, SdoAbort

ESM_STATES = (AlState.INIT, AlState.PREOP, AlState.SAFEOP, AlState.OP)


# ---- construction and power ---------------------------------------------------------------------
@pytest.mark.parametrize(("kwargs", "message"), [
    ({"modules": [("DI16", {})] * 17}, "at most 16"),
    ({"modules": [], "rotary_switch": 0}, "1..15"),
    ({"modules": [], "rotary_switch": 16}, "1..15"),
    ({"modules": [("DB16", {}), ("XX9", {})]}, "slot 2: unknown FastCAT module type"),
    ({"modules": [("DB16", {"bogus": 1})]}, "slot 1 \\(DB16\\)"),
])
def test_construction_errors(kwargs: dict, message: str) -> None:
    """§2: at most 16 modules; §6.19: rotary 1..15; module names from the §2 catalog."""
    with pytest.raises(ValueError, match=message):
        FastCat("fastcat", random.Random(0), **kwargs)


def test_nine_analog_modules_construct_then_alarm_at_scan() -> None:
    """§2 / §7.5 0x15: more than 8 analog modules is a scan-time alarm, byte 0 = position of
    the 8th analog module."""
    bench = Bench(["DB16"] + ["AI8D"] * 9)
    bench.settle()
    assert bench.emergencies() == ["09 00 00 15 00"]  # analog modules at 2..10: 8th at 9
    assert bench.fc.snapshot()["leds"]["ERR"] == "blinking"


def test_power_off_and_on() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("power", on=False)
    snap = bench.fc.snapshot()
    assert snap["esm"] == "INIT" and not snap["powered"] and not bench.fc.reachable()
    assert set(snap["leds"].values()) == {"off"}
    with pytest.raises(CommandError, match="not powered"):
        bench.read(0x1000, 0)
    bench.apply("power", on=True)
    t0 = bench.now
    bench.settle()
    assert bench.now - t0 == scan_us(3)
    assert bench.read(0x1000, 0) == 0x1389


def test_scan_time_grows_with_modules() -> None:
    """§3: the INIT scan takes longer with more modules."""
    times = []
    for modules in (["DI16"], ["DI16"] * 6):
        bench = Bench(modules)
        bench.settle()
        times.append(bench.now)
    assert times == [scan_us(1), scan_us(6)]


# ---- ESM ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("current", ESM_STATES)
@pytest.mark.parametrize("target", (*ESM_STATES, AlState.BOOT))
def test_esm_requests(current: AlState, target: AlState) -> None:
    """ETG.1000.6 transitions; others answer §7.7 0x0011 with the error flag, INIT -> BOOT
    0x0013 "Bootstrap not supported" (ETG.1000.6 gives 0x0013 to I -> B only: P / S / O -> B
    are invalid transitions, 0x0011, as Beckhoff SSC AL_ControlInd and SOES ESC_state answer)."""
    bench = Bench()
    if current is AlState.INIT:
        bench.settle()
    else:
        bench.to_state(current)
    bench.fc.request_state(target)
    if target is AlState.INIT and current is not AlState.INIT:
        assert bench.fc.al_state is AlState.INIT and bench.fc.scan is not None
    elif target is current or (current, target) in ALLOWED_TRANSITIONS:
        assert (bench.fc.al_state, bench.fc.al_status, bench.fc.al_status_code) == \
            (target, int(target), 0)
    else:
        code = 0x0013 if (current, target) == (AlState.INIT, AlState.BOOT) else 0x0011
        # A refusal in OP lands in SAFEOP (ETG.1000.6; SSC AL_ControlInd, SOES ESC_state).
        left = AlState.SAFEOP if current is AlState.OP else current
        assert (bench.fc.al_state, bench.fc.al_status, bench.fc.al_status_code) == \
            (left, int(left) | 0x10, code)
        assert bench.fc.snapshot()["leds"]["ERR"] == "blinking"  # ETG.1300: refused


@pytest.mark.parametrize("request_", ("boot", "unknown"))
def test_a_request_refused_in_op_drops_to_safeop_with_outputs_off(request_: str) -> None:
    """ETG.1000.6 (SSC AL_ControlInd, SOES ESC_state): a request the coupler refuses in OP
    (BOOT: 0x0011, an invalid transition from OP; an unknown state: 0x0012) leaves it in
    SAFEOP + error, its outputs in the safe state as after a requested OP -> SAFEOP; RUN
    single flash, ERR blinking."""
    bench = Bench(["DO16", "AI8D"])
    bench.to_state(AlState.OP)
    bench.write(0x7000, 1, 1)
    bench.step()
    assert bench.fc.snapshot()["rail"][0]["do"][0] is True
    mark = bench.mark()
    if request_ == "boot":
        bench.fc.request_state(AlState.BOOT)
    else:  # AL control 0x05, as the wire face hands it to the ESM
        bench.fc.esm.request_unknown(0x05, False, bench.fc.now_us)
    bench.step()
    code = "0x0011" if request_ == "boot" else "0x0012"
    assert (bench.fc.al_state, bench.fc.al_status) == (AlState.SAFEOP, 0x14)
    assert [(r["event"], r.get("code"), r.get("to")) for r in bench.records(since=mark)
            if r["event"] in ("al_status", "state")] == [
        ("al_status", code, None), ("state", None, "SAFEOP")]
    snap = bench.fc.snapshot()
    assert snap["rail"][0]["do"][0] is False
    assert (snap["leds"]["RUN"], snap["leds"]["ERR"]) == ("single_flash", "blinking")
    assert bench.read(0x7000, 1) == 1  # the master's image is kept for the next OP


def test_the_error_flag_is_acknowledged_with_al_control_bit_4() -> None:
    """ETG.1000.6 "Error Ind Ack" (SSC AL_ControlInd): without bit 4 a request over the
    error flag is ignored, the ERR LED keeps blinking; with it the flag and code clear."""
    bench = Bench()
    bench.to_state(AlState.PREOP)
    bench.fc.request_state(AlState.OP)  # PREOP -> OP is not a transition: 0x0011
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x12, 0x0011)
    for target in (AlState.PREOP, AlState.SAFEOP):
        bench.fc.request_state(target)
        assert (bench.fc.al_status, bench.fc.al_status_code) == (0x12, 0x0011)
        assert bench.fc.snapshot()["leds"]["ERR"] == "blinking"
    bench.fc.request_state(AlState.PREOP, ack=True)
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x02, 0)
    assert bench.fc.snapshot()["leds"]["ERR"] == "off"


@pytest.mark.parametrize(("state", "run"), [
    (AlState.INIT, "off"), (AlState.PREOP, "blinking"), (AlState.SAFEOP, "single_flash"),
    (AlState.OP, "on"),
])
def test_run_led(state: AlState, run: str) -> None:
    """ETG.1300 RUN indicator per ESM state."""
    bench = Bench()
    if state is AlState.INIT:
        bench.settle()
    else:
        bench.to_state(state)
    bench.step()
    assert bench.fc.snapshot()["leds"]["RUN"] == run


def test_outputs_follow_only_in_op_without_alarm() -> None:
    """§6.28: 0x7000 drives the outputs; FieldRig enables them in OP without alarm only."""
    bench = Bench(["DO16", "AI8D"])
    bench.to_state(AlState.SAFEOP)
    bench.write(0x7000, 1, 1)
    bench.step()
    assert bench.fc.snapshot()["rail"][0]["do"][0] is False
    bench.fc.request_state(AlState.OP)
    bench.step()
    assert bench.fc.snapshot()["rail"][0]["do"][0] is True
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.step()
    bench.step()
    assert bench.fc.snapshot()["rail"][0]["do"][0] is False


# ---- object dictionary --------------------------------------------------------------------------
def test_identity_objects() -> None:
    """§6.1-§6.5."""
    bench = Bench()
    bench.settle()
    assert bench.read(0x1000, 0) == 0x0000_1389  # 5001 = MDP
    assert (bench.read(0x1008, 0), bench.read(0x1009, 0), bench.read(0x100A, 0)) == \
        ("FastCAT", "1.0", "1.0")
    assert [bench.read(0x1018, s) for s in (0, 1, 2)] == [4, 0xC6, 0xFACA]
    assert bench.read("0x1018", "4") == bench.fc.serial  # "0x..." strings accepted


def test_pdo_layout_is_generated_and_read_only() -> None:
    """§5: 0x1600+N-1 / 0x1A00+N-1 from the modules, 0x16FF / 0x1AFF always, 0x1C12 / 0x1C13;
    the mapping cannot be modified."""
    bench = Bench()
    bench.settle()
    od = bench.fc.od
    for n, module in enumerate(bench.fc.bound, start=1):
        for base, entries in ((0x1600, module.rx_entries(n)), (0x1A00, module.tx_entries(n))):
            assert od.read(base + n - 1, 0) == len(entries)
            got = [od.read(base + n - 1, s) for s in range(1, len(entries) + 1)]
            assert got == [i << 16 | s << 8 | b for i, s, b in entries]
    # §6.16 / §6.17: "1 Fault active / Reset fault BOOL (1)", "2:8 Reserved (7)": the bit and
    # seven reserved bits, one byte, so the modules' data start byte-aligned (a 7-bit gap)
    assert [bench.read(0x16FF, s) for s in range(3)] == [2, 0x5200_0101, 0x0000_0007]
    assert [bench.read(0x1AFF, s) for s in range(3)] == [2, 0x5100_0101, 0x0000_0007]
    assert [bench.read(0x1C12, s) for s in range(bench.read(0x1C12, 0) + 1)][1:] == \
        [0x16FF, 0x1600]  # only the DB16 has outputs
    assert [bench.read(0x1C13, s) for s in range(1, bench.read(0x1C13, 0) + 1)] == \
        [0x1AFF, 0x1A00, 0x1A01, 0x1A02]  # §4 Sirio example order
    tx = bench.fc.bound[2].tx_entries(3)
    assert tx[0][0] == 0x6420  # §4: AI8C as module 3 maps 0x6420:1..8
    with pytest.raises(SdoAbort) as exc:
        bench.write(0x1A01, 1, 0)
    assert exc.value.code is AbortCode.READ_ONLY
    with pytest.raises(SdoAbort):
        bench.write(0x1C13, 0, 0)


def test_coupler_objects() -> None:
    """§6.16-§6.23, §6.31."""
    bench = Bench(rotary_switch=7, master_address=7)
    bench.settle()
    assert [bench.read(0x5100, s) for s in (0, 1)] == [8, False]
    assert [bench.read(0x5200, s) for s in (0, 1)] == [8, False]
    assert bench.read(0x5300, 0) == 3 and bench.read(0x5300, 3) == 0
    assert bench.read(0x5301, 0) == 0
    bench.write(0x5301, 0, 1)  # §6.19 prints ro but "impostando a 1": writable (docs)
    assert bench.read(0x5301, 0) == 1
    with pytest.raises(SdoAbort) as exc:
        bench.write(0x5301, 0, 2)
    assert exc.value.code is AbortCode.VALUE_TOO_HIGH
    assert bench.read(0x5302, 0) == 7
    assert bench.read(0x5310, 0) == 16 and bench.read(0x5320, 0) == 16
    assert bench.read(0x5400, 0) == 0
    assert [bench.read(0xF050, s) for s in (1, 2, 3)] == \
        [CATALOG[m].product_code for m in THREE]
    for index, sub in ((0x5100, 1), (0x5302, 0), (0x5400, 0), (0xF050, 1), (0x1000, 0)):
        with pytest.raises(SdoAbort):
            bench.write(index, sub, 1)
    bench.write(0x5200, 1, True)  # a TOML boolean is taken for a BOOL object
    assert bench.read(0x5200, 1) == 1


def test_module_objects_are_added_per_module_number() -> None:
    """§6: per-module objects at base + 0x10 * (N - 1)."""
    bench = Bench()
    bench.settle()
    assert bench.fc.od.has_index(0x2004)  # DB16 is module 1
    assert bench.fc.od.has_index(0x6410) and bench.fc.od.has_index(0x6420)


# ---- alarms -------------------------------------------------------------------------------------
@pytest.mark.parametrize("row", list(COUPLER_CODES.values()), ids=lambda r: r.symbol)
def test_inject_every_coupler_code(row: AlarmCode) -> None:
    """§7 / §7.5: emergency FF00 / 81, byte 3 = code, byte 0 = module (0 for a code about no
    node), mirrored in 0x5400 and 0x5100:1; in OP: OP -> PREOP with 0x80XX (§7.7)."""
    bench = Bench()
    bench.to_state(AlState.OP)
    mark = bench.mark()
    module = 2 if row.names_module else None
    n = module or 0
    bench.apply("inject_fault", module=module, fault=row.symbol)
    bench.step()
    rec = bench.records(since=mark)
    emergency = [r for r in rec if r["event"] == "emergency"]
    assert emergency == [{"t": emergency[0]["t"], "device": "fastcat", "event": "emergency",
                          "code": "0xFF00", "register": "0x81",
                          "data": f"{n:02X} 00 00 {row.code:02X} 00"}]
    assert bench.read(0x5400, 0) == row.code << 24 | n
    assert bench.read(0x5100, 1) is True
    assert [r["code"] for r in rec if r["event"] == "al_status"] == [
        f"0x80{row.code:02X}" if module is None else f"0x82{row.code:02X}"]
    assert bench.fc.al_state is AlState.PREOP and bench.fc.al_status == 0x12
    alarm = bench.fc.snapshot()["alarm"]
    assert (alarm["table"], alarm["code"], alarm["name"], alarm["module"]) == \
        ("coupler", row.code, row.symbol, n)
    bench.apply("clear_fault", module=module, fault=row.symbol)
    bench.step()
    assert bench.fc.alarm is not None  # latched until reset
    bench.reset_fault()
    assert bench.fc.alarm is None and bench.read(0x5400, 0) == 0


@pytest.mark.parametrize("row", list(MODULE_CODES.values()), ids=lambda r: r.symbol)
def test_inject_every_module_code(row: AlarmCode) -> None:
    """§7.6: byte 2 = module code, byte 0 = module; the ESM stays in OP with no AL status code
    (§7.7 carries coupler alarms only, docs "Module alarms keep OP"); Reset fault clears it."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", module=3, fault=f"module:0x{row.code:02X}")
    bench.step()
    assert bench.emergencies() == [f"03 00 {row.code:02X} 00 00"]
    assert bench.read(0x5400, 0) == row.code << 16 | 3
    assert bench.read(0x5100, 1) is True
    assert bench.fc.al_state is AlState.OP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x08, 0)
    assert bench.records("al_status") == []
    bench.apply("clear_fault", module=3, fault=row.symbol)
    bench.reset_fault()
    assert bench.fc.alarm is None and bench.fc.al_state is AlState.OP


def test_module_fault_needs_a_module_and_bare_codes_are_refused() -> None:
    bench = Bench()
    bench.settle()
    with pytest.raises(CommandError, match="module alarm"):
        bench.apply("inject_fault", fault="TARATURA")
    with pytest.raises(CommandError, match="ambiguous"):
        bench.apply("inject_fault", module=2, fault="0x04")
    with pytest.raises(CommandError, match="not injected"):
        bench.apply("clear_fault", fault="LINK_LOSS")


def test_only_the_first_alarm_is_reported() -> None:
    """§7: the coupler reports the first alarm; later ones send nothing until a reset, then
    the next present cause is raised with a new emergency."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", module=1, fault="CRC_PDORX")
    bench.step()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(0.5)
    assert bench.emergencies() == ["01 00 00 05 00"]
    bench.apply("clear_fault", module=1, fault="CRC_PDORX")
    bench.reset_fault()
    assert bench.emergencies() == ["01 00 00 05 00", "02 00 0B 00 00"]
    assert bench.fc.snapshot()["alarm"]["table"] == "module"  # never both tables at once


def test_coupler_alarm_puts_every_module_in_alarm() -> None:
    """§7: any alarm -> all modules in alarm: red on, yellow off (docs LED table)."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.step()
    assert not any(m.in_alarm for m in bench.fc.modules())
    bench.apply("inject_fault", fault="SDO_ERROR")
    bench.step()
    assert all(m.in_alarm for m in bench.fc.modules())
    leds = bench.fc.snapshot()["leds"]
    assert [leds[f"{k}.red"] for k in (1, 2, 3)] == ["on"] * 3
    assert [leds[f"{k}.yellow"] for k in (1, 2, 3)] == ["off"] * 3
    assert leds["ERR"] == "single_flash"  # local error: OP left autonomously
    bench.apply("clear_fault", fault="SDO_ERROR")
    bench.reset_fault()
    bench.step()
    assert not any(m.in_alarm for m in bench.fc.modules())
    leds = bench.fc.snapshot()["leds"]
    assert [leds[f"{k}.yellow"] for k in (1, 2, 3)] == ["blinking"] * 3


def test_reset_fault_needs_the_cause_gone_and_a_rising_edge() -> None:
    """§6.17 / §7: Reset fault resets only once the cause is gone; holding the bit high does
    not reset twice."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("calibrated", module=2, value=False)  # forwarded to the AI8D (§7.6 0x0B)
    bench.step()
    assert bench.emergencies() == ["02 00 0B 00 00"]  # the §7.2 example
    bench.reset_fault()
    assert bench.fc.alarm is not None and bench.fc.snapshot()["alarm"]["cause_present"]
    bench.apply("calibrated", module=2, value=True)
    bench.write(0x5200, 1, 1)  # still high: no edge
    assert bench.fc.alarm is not None and not bench.fc.snapshot()["alarm"]["cause_present"]
    bench.write(0x5200, 1, 0)
    bench.write(0x5200, 1, 1)
    assert bench.fc.alarm is None
    bench.apply("inject_fault", fault="TMO_SDORD")
    bench.step()
    bench.apply("clear_fault", fault="TMO_SDORD")
    bench.write(0x5200, 1, 1)  # held high since the last reset
    assert bench.fc.alarm is not None
    bench.apply("set_reset_fault", on=False)
    bench.apply("set_reset_fault", on=True)
    assert bench.fc.alarm is None


def test_codes_above_0x7f_need_a_resync(monkeypatch: pytest.MonkeyPatch) -> None:
    """§7 / §7.5: coupler codes above 0x7F are not resettable by Reset fault; a resync
    (INIT) resets them once the cause is gone. No printed code is above 0x7F: a test row."""
    monkeypatch.setitem(COUPLER_CODES, 0x80, AlarmCode("coupler", 0x80, "TEST_FATAL", "test"))
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", fault="coupler:0x80")
    bench.step()
    assert bench.emergencies() == ["00 00 00 80 00"] and bench.fc.al_status_code == 0x8080
    assert not bench.fc.snapshot()["alarm"]["resettable"]
    bench.apply("clear_fault", fault="TEST_FATAL")
    bench.reset_fault()
    assert bench.fc.alarm is not None
    bench.fc.request_state(AlState.INIT)
    bench.run_until(lambda: bench.fc.scan is None)
    assert bench.fc.alarm is None


def test_resync_keeps_an_alarm_whose_cause_is_present() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", fault="LINK_LOSS")
    bench.step()
    bench.fc.request_state(AlState.INIT)
    bench.run_until(lambda: bench.fc.scan is None)
    assert bench.fc.alarm is not None


# ---- physical causes ----------------------------------------------------------------------------
def test_the_rail_takes_sixteen_modules() -> None:
    """§2 "fino ad un massimo di 16 moduli": no 17th position to plug into or swap with (the
    scan, the object dictionary and the PDOs number modules 1..16); the rail is unchanged and
    a rescan still works."""
    bench = Bench(["DI16"] * 16)
    bench.settle()
    for action, args in (("plug", {"module": 17, "type": "DI16"}),
                         ("swap", {"module": 17, "other": 1})):
        with pytest.raises(CommandError, match="at most 16 modules"):
            bench.apply(action, **args)
    assert len(bench.fc.rail) == 16
    bench.fc.request_state(AlState.PREOP)
    bench.fc.request_state(AlState.INIT)
    bench.run_until(lambda: bench.fc.scan is None)
    assert bench.read(0x5300, 0) == 16


def test_unplug_in_op_is_missing_node_answer() -> None:
    """§7.1 / §7.7: a module unplugged in OP -> 0x04 for module 2, 0x8204, OP -> PREOP;
    §6.18 counts the failed exchanges; plugged back, a Reset fault clears it."""
    bench = Bench()
    bench.to_state(AlState.OP)
    mark = bench.mark()
    bench.apply("unplug", module=2)
    bench.run(0.010)
    rec = [r for r in bench.records(since=mark) if r["event"] != "led"]
    assert [(r["event"], r.get("data") or r.get("code") or r.get("to")) for r in rec] == [
        ("alarm", "0x04"), ("emergency", "02 00 00 04 00"), ("al_status", "0x8204"),
        ("state", "PREOP")]
    assert bench.read(0x5300, 2) == 10 and bench.read(0x5300, 1) == 0
    assert bench.fc.snapshot()["rail"][1] == {"slot": 2, "type": None, "expected": "AI8D",
                                              "expected_from": "last scan"}
    bench.reset_fault()
    assert bench.fc.alarm is not None  # still missing
    bench.apply("plug", module=2, type="AI8D")
    bench.step()
    bench.reset_fault()
    assert bench.fc.alarm is None
    bench.fc.request_state(AlState.SAFEOP, ack=True)  # AL control bit 4 (ETG.1000.6)
    bench.fc.request_state(AlState.OP)
    assert bench.fc.al_state is AlState.OP


def test_module_power_off_is_missing_node_answer() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("module_power", module=3, on=False)
    bench.step()
    assert bench.emergencies() == ["03 00 00 04 00"]
    bench.step()
    assert bench.fc.snapshot()["leds"]["3.red"] == "off"  # no supply, no LED


def test_swap_different_types_is_module_changed_same_types_unnoticed() -> None:
    bench = Bench(["DI16", "DI16", "AI8D"])
    bench.to_state(AlState.OP)
    bench.apply("swap", module=1, other=2)
    bench.run(0.005)
    assert bench.emergencies() == []  # two DI16: the coupler cannot tell
    bench.apply("swap", module=2, other=3)
    bench.step()
    assert bench.emergencies() == ["02 00 00 01 00"]


def test_low_tbus_voltage() -> None:
    """§7.6 0x0C, byte 0 = the first module."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("tbus_voltage", low=True)
    bench.step()
    assert bench.emergencies() == ["01 00 0C 00 00"]
    assert bench.fc.snapshot()["tbus_low"]


def test_link_loss() -> None:
    """§7.5 0x13: the cable out; the master cannot reach the slave meanwhile."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("link", connected=False)
    bench.step()
    assert bench.emergencies() == ["00 00 00 13 00"]
    assert not bench.fc.reachable() and bench.fc.snapshot()["leds"]["LINK"] == "off"
    assert bench.fc.take_emergencies() == []
    bench.apply("link", connected=True)
    assert bench.fc.take_emergencies() == [bytes.fromhex("00FF81" "0000001300")]  # 8-byte frame


def unread_emergency() -> Bench:
    """§7.5 0x13 with the cable out in OP: queued, the master cannot read it."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("link", connected=False)
    bench.step()
    assert bench.emergencies() == ["00 00 00 13 00"] and bench.fc.take_emergencies() == []
    bench.apply("link", connected=True)
    return bench


@pytest.mark.parametrize("way", ["request", "cnf"])
def test_unread_emergencies_are_lost_through_init(way: str) -> None:
    """The mailbox stops on the way to INIT, a master's request or the CNF procedure, and its
    queue goes (ETG.1000.6, SSC MBX_StopMailboxHandler)."""
    bench = unread_emergency()
    if way == "request":
        bench.fc.request_state(AlState.INIT)
    else:
        bench.apply("hold_cnf", seconds=3.0)
        bench.run(3.1)
    assert bench.fc.al_state is AlState.INIT
    bench.fc.request_state(AlState.PREOP)
    bench.run_until(lambda: bench.fc.al_state is AlState.PREOP)
    assert bench.fc.take_emergencies() == []


def test_unread_emergencies_wait_without_init() -> None:
    bench = unread_emergency()
    bench.run(0.01)
    assert bench.fc.take_emergencies() == [bytes.fromhex("00FF81" "0000001300")]


def test_no_module_on_the_bus() -> None:
    """§7.5 0x10 NO_MOD; a booting error: ERR flickering (docs)."""
    bench = Bench([])
    bench.settle()
    assert bench.emergencies() == ["00 00 00 10 00"]
    assert bench.fc.snapshot()["leds"]["ERR"] == "flickering"


def test_address_check_on_the_transition_to_op() -> None:
    """§6.19: with 0x5301 = 1, rotary (0x5302) != master address -> 0x12, 0x5400 =
    0x12000000, OP refused; the switch is read at power-up."""
    bench = Bench(rotary_switch=3, master_address=1)
    bench.to_state(AlState.SAFEOP)
    bench.write(0x5301, 0, 1)
    bench.fc.request_state(AlState.OP)
    assert bench.fc.al_state is AlState.PREOP
    assert bench.read(0x5400, 0) == 0x1200_0000
    assert bench.fc.al_status_code == 0x8012
    bench.apply("set_rotary", value=1)
    bench.reset_fault()
    assert bench.fc.alarm is not None  # the switch is only read at power-up
    bench.apply("power", on=False)
    bench.apply("power", on=True)
    bench.to_state(AlState.SAFEOP)
    bench.write(0x5301, 0, 1)
    bench.fc.request_state(AlState.OP)
    assert bench.fc.al_state is AlState.OP and bench.read(0x5302, 0) == 1


@pytest.mark.parametrize(("rotary", "station", "op"), [
    (3, 3, True),  # the wire master's 0x0010 decides, not master_address (1)
    (1, 1001, False),  # TwinCAT's default EtherCAT Addr: above 15, never the switch
    (3, 0x0103, False),  # compared whole: the low byte alone is not the address
])
def test_address_check_compares_the_wire_masters_station_address(rotary: int, station: int,
                                                                  op: bool) -> None:
    """§6.19 «l'indirizzo logico assegnato dal master Ethercat»: with a master on the wire, the
    configured station address it wrote (ESC 0x0010); ``master_address`` is the built-in
    master's (docs/fastcat-coupler.md "Address check")."""
    bench = Bench(rotary_switch=rotary, master_address=1)
    bench.fc.take_station_address(station)
    bench.to_state(AlState.SAFEOP)
    bench.write(0x5301, 0, 1)
    bench.fc.request_state(AlState.OP)
    assert (bench.fc.al_state is AlState.OP) is op
    assert bench.read(0x5400, 0) == (0 if op else 0x1200_0000)


def test_the_wire_masters_address_corrected_lets_reset_fault_clear_0x12() -> None:
    """The cause of 0x12 is the mismatch: once the master writes the switch's address, the
    Reset fault edge (§6.17) clears the alarm; None hands the check back to the built-in
    master's master_address."""
    bench = Bench(rotary_switch=3, master_address=3)
    bench.fc.take_station_address(1001)
    bench.to_state(AlState.SAFEOP)
    bench.write(0x5301, 0, 1)
    bench.fc.request_state(AlState.OP)
    assert bench.fc.al_status_code == 0x8012
    bench.reset_fault()
    assert bench.fc.alarm is not None  # cause present: refused
    bench.fc.take_station_address(None)  # the built-in master's 3 again
    bench.reset_fault()
    assert bench.fc.alarm is None


def test_address_check_disabled_by_default() -> None:
    bench = Bench(rotary_switch=3, master_address=1)
    bench.to_state(AlState.OP)
    assert bench.fc.alarm is None


# ---- module actions, LEDs, views ----------------------------------------------------------------
def test_module_actions_are_forwarded_to_the_rail_position() -> None:
    bench = Bench()
    bench.settle()
    assert "set_analog" in FastCat.ACTIONS and FastCat.ACTIONS["set_analog"].module == "required"
    bench.apply("set_analog", module=2, channel=1, value=5.0)
    assert bench.fc.rail[1].ai.field[0] == 5.0
    with pytest.raises(CommandError, match="needs a module"):
        bench.fc.apply("set_analog", {"channel": 1, "value": 1.0})
    with pytest.raises(CommandError, match="no module at rail position 5"):
        bench.apply("set_analog", module=5, channel=1, value=1.0)
    with pytest.raises(CommandError):
        bench.apply("set_shaft_speed", module=1, encoder=1, rpm=10.0)  # a DB16


def test_link_led_shows_traffic() -> None:
    """ETG.1300 L/A: on = link without traffic, flickering = traffic."""
    bench = Bench(master=True)
    bench.settle()
    assert bench.fc.snapshot()["leds"]["LINK"] == "flickering"
    alone = Bench()
    alone.settle()
    assert alone.fc.snapshot()["leds"]["LINK"] == "on"


def test_led_events_only_on_change() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    mark = bench.mark()
    bench.run(1.0)
    assert bench.led_events(mark) == []


def test_snapshot_keys() -> None:
    bench = Bench()
    bench.settle()
    snap = bench.fc.snapshot()
    assert set(snap) >= {
        "kind", "id", "powered", "esm", "requested", "al_status", "al_status_code",
        "station_address", "rotary_switch", "address_check", "fault_active", "emergency_data",
        "alarm", "injected", "link", "tbus_low", "cnf", "scan", "leds", "rail",
        "stored_config", "detected"}
    assert snap["kind"] == "fastcat" and snap["scan"] == {"active": False, "done": 3, "total": 3}
    assert snap["rail"][0]["slot"] == 1 and snap["rail"][0]["detected_as"] == "DB16"


def test_same_commands_same_events() -> None:
    """Determinism: a replay of the same commands gives the same event records."""
    def run() -> list[dict]:
        bench = Bench(["DB16", "AI8D", "AX2"], master=True)
        bench.run(3.0)
        bench.apply("set_shaft_speed", module=3, encoder=1, rpm=600.0)
        bench.apply("unplug", module=2)
        bench.run(1.0)
        bench.apply("plug", module=2, type="AI8D")
        bench.reset_fault()
        bench.apply("hold_cnf", seconds=3.2)
        bench.run(9.0)
        return bench.records()
    assert run() == run()


def test_a_module_fault_without_a_module_is_refused_by_the_command_check() -> None:
    """The scenario check before a run calls check_command only: the rule must sit there."""
    fc = Bench().fc
    with pytest.raises(CommandError, match=r"module alarm \(§7.6\): target 'fastcat/N'"):
        fc.check_command("inject_fault", {"fault": "module:0x04"})
    fc.check_command("inject_fault", {"fault": "module:0x04"}, module=3)
    fc.check_command("inject_fault", {"fault": "MISSING_NODE_ANSWER"})
