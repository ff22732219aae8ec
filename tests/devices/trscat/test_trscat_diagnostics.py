"""Diagnostics of the TRS-CAT: the application errors of seed 001 §9.3.7 with their
consequences, 0xF100 and 0x1AFF (§9.3.4), the 0x10F3 history in acknowledge mode (§9.3.7)."""

from __future__ import annotations

import struct

import pytest
from trscat_bench import Bench

from app.ethercat_wire.faces.trscat import TrsCatFace
from app.ui.panels.object_dictionary import read_rows, render
from devices.device import CommandError
from devices.ethercat import AlState
from devices.od import DataType, SdoAbort
from devices.trscat.diagnostics import (
    FAULTS,
    MAX_MESSAGES,
    Bus,
    DiagHistory,
    DiagMessage,
    DiagType,
    parse_fault,
)

# §9.3.7 as printed: code -> (family, consequence).
SEED_CODES = {
    0xA000: "configuration",
    0x7100: "internal hardware",
    0x7500: "internal hardware",
    0x5114: "AN-E +12V",
    0x5115: "AN-E -12V",
    0x3220: "field +24V",
    0x6100: "internal software",
}


def test_every_seed_code_has_a_fault() -> None:
    assert {f.code for f in FAULTS.values()} == set(SEED_CODES)


@pytest.mark.parametrize("fault", FAULTS.values(), ids=lambda f: f.name)
def test_consequences(fault) -> None:
    """§9.3.7: internal hardware errors shut the TRS bus down; the software error also
    deadlocks the ESM; the others do neither."""
    family = SEED_CODES[fault.code]
    assert fault.bus_shutdown is family.startswith("internal")
    assert fault.deadlock is (family == "internal software")


# (fault, module, expansions, 0xF100:1 expected, bus flags (2, 3, 4) expected, bus state)
INJECTIONS = [
    ("CONFIG_ERROR", None, ["IO-E"], 0b11, (True, True, True), "running"),
    ("TRS_OVERCURRENT", None, ["IO-E"], 0, (True, True, False), "shutdown"),
    ("TRS_UNDERVOLTAGE", None, ["IO-E"], 0, (True, False, True), "shutdown"),
    ("TRS_COMM_ERROR", None, ["IO-E"], 0, (False, True, True), "shutdown"),
    ("AN_PLUS_12V", 1, ["AN-E", "IO-E"], 0b101, (True, True, True), "running"),
    ("AN_MINUS_12V", 1, ["AN-E"], 0b01, (True, True, True), "running"),
    ("FIELD_SUPPLY", None, ["IO-E"], 0b10, (True, True, True), "running"),
    ("FIELD_SUPPLY", 1, ["IO-E"], 0b01, (True, True, True), "running"),
    ("SOFTWARE_ERROR", None, ["IO-E"], 0, (False, True, True), "shutdown"),
]


@pytest.mark.parametrize(("name", "module", "expansions", "status", "flags", "bus"),
                         INJECTIONS, ids=[f"{i[0]}@{i[1]}" for i in INJECTIONS])
def test_injected_faults(name: str, module: int | None, expansions: list[str], status: int,
                         flags: tuple[bool, bool, bool], bus: str) -> None:
    """§9.3.4 / §9.3.7: 0xF100:1 bit per slot, :2..:4 bus status, the 0x10F3 message with
    the slot as parameter, 0x1AFF:5 "New message available", BUS LED (§8.2)."""
    bench = Bench(expansions, configured=expansions)
    bench.to_state(AlState.OP)
    assert bench.read(0xF100, 1) == (1 << (len(expansions) + 1)) - 1
    bench.apply("inject_fault", module=module, fault=name)
    bench.run(0.003)
    fault = FAULTS[name]
    assert bench.read(0xF100, 1) == status
    assert tuple(bench.read(0xF100, s) for s in (2, 3, 4)) == flags
    assert bench.trs.snapshot()["trs_bus"]["state"] == bus
    assert bench.leds()["BUS"] == ("on" if bus == "running" else "off")
    message = bench.messages()[0]
    assert message["diag_code"] == f"0xE800{fault.code:04X}"
    assert message["params"] == ([] if fault.target.value == "device" else [module or 0])
    assert bench.read(0x10F3, 4) is True
    assert bench.read(0x1001, 0) == fault.register
    alarms = bench.records("alarm")
    assert (alarms[0]["code"], alarms[0]["name"]) == (f"0x{fault.code:04X}", name)
    if fault.deadlock:
        assert bench.trs.al_state is AlState.PREOP and bench.leds()["ERROR"] == "on"
        bench.request(AlState.SAFEOP)
        assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.PREOP, 0x0001)
        bench.request(AlState.INIT)  # down is allowed, and back to PRE-OP: the deadlock
        bench.request(AlState.PREOP)
        bench.request(AlState.SAFEOP)
        assert bench.trs.al_state is AlState.PREOP and bench.leds()["ERROR"] == "on"
    elif name != "CONFIG_ERROR":
        assert bench.trs.al_state is AlState.OP  # "continua ad essere operativo su EtherCAT"


@pytest.mark.parametrize("name", [f.name for f in FAULTS.values() if f.bus_shutdown])
def test_shutdown_is_irreversible_until_power_off(name: str) -> None:
    """§8.2 / §9.3.7 "shutdown irreversibile del bus TRS": clearing the cause does not bring
    the bus back; switching the logic supply off and on does."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", fault=name)
    bench.run(0.002)
    bench.apply("clear_fault", fault=name)
    bench.run(0.01)
    snap = bench.trs.snapshot()
    # The review (21_trscat_cleared.png): nothing said the shutdown is latched, and Outputs
    # read "normal" (the OP mode) while every slot's outputs were off.
    assert snap["trs_bus"]["state"] == "shutdown" and snap["trs_bus"]["latched"] is True
    assert snap["outputs_stopped"] == "bus down"
    bench.apply("power", on=False)
    assert bench.trs.snapshot()["outputs_stopped"] == "node off"
    bench.apply("power", on=True)
    bench.to_state(AlState.OP)
    snap = bench.trs.snapshot()
    assert snap["trs_bus"]["state"] == "running" and snap["trs_bus"]["latched"] is False
    assert snap["outputs_stopped"] is None
    assert bench.read(0xF100, 1) == 1 and not bench.trs.snapshot()["alarms"]


def test_each_bus_status_shows_its_own_fault_after_the_shutdown() -> None:
    """§9.3.4 0xF100:2 / :3 / :4 (TRUE = OK) each report a kind of TRS bus fault: one raised
    once the bus is already down (an instructor's second cause) makes its sub FALSE as well,
    as its 0x10F3 message and 0x1001 say, and the sub is TRUE again when it is cleared while
    the sub of the fault that shut the bus stays FALSE until power-off."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", fault="TRS_OVERCURRENT")
    bench.run(0.002)
    assert [bench.read(0xF100, s) for s in (2, 3, 4)] == [True, True, False]
    bench.apply("inject_fault", fault="TRS_UNDERVOLTAGE")
    bench.run(0.002)
    assert bench.messages()[-1]["text"].endswith("undervoltage")
    assert [bench.read(0xF100, s) for s in (2, 3, 4)] == [True, False, False]
    bench.apply("clear_fault", fault="TRS_UNDERVOLTAGE")
    bench.apply("clear_fault", fault="TRS_OVERCURRENT")
    bench.run(0.002)
    assert [bench.read(0xF100, s) for s in (2, 3, 4)] == [True, True, False]


def test_reversible_faults_clear_with_their_cause() -> None:
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", module=1, fault="0x5114")
    bench.run(0.002)
    assert bench.read(0xF100, 1) == 0b01
    bench.apply("clear_fault", module=1, fault="AN_PLUS_12V")
    bench.run(0.002)
    assert bench.read(0xF100, 1) == 0b11
    assert [r["active"] for r in bench.records("alarm")] == [True, False]


# ---- physical causes -------------------------------------------------------------------------
def test_field_supply_out_of_range() -> None:
    """§8.4 / §9.3.7 0x3220 on the base: +24V LED off, outputs unpowered, slot 0 in error."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    bench.apply("set_output", channel=1, value=1)
    bench.run(0.002)
    assert bench.leds()["+24V"] == "on" and bench.leds()["I/O 1"] == "on"
    bench.apply("field_supply", volts=16.0)
    bench.run(0.002)
    assert bench.leds()["+24V"] == "off" and bench.leds()["I/O 1"] == "off"
    assert bench.read(0xF100, 1) == 0b10
    assert bench.messages()[0]["code"] == "0x3220" and bench.messages()[0]["params"] == [0]
    bench.apply("field_supply", volts=24.0)
    bench.run(0.002)
    assert bench.read(0xF100, 1) == 0b11 and bench.leds()["I/O 1"] == "on"


def test_injected_field_supply_fault_puts_the_24v_led_out() -> None:
    """§8.4 "È spento quando l'alimentazione è assente o fuori dal range di ammissibilità", §4
    "Controllo software e segnalazione a led": 0x3220 injected on the base is that software
    check failing, so the LED goes off as for the physical cause; it comes back when the
    injection is cleared. An expansion's own 0x3220 leaves the base's LED alone."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    bench.apply("set_output", channel=1, value=1)
    bench.run(0.01)
    bench.apply("inject_fault", fault="0x3220")
    bench.run(0.01)
    assert bench.read(0xF100, 1) == 0b10 and bench.leds()["I/O 1"] == "off"
    assert bench.leds()["+24V"] == "off"
    bench.apply("clear_fault", fault="0x3220")
    bench.run(0.01)
    assert bench.read(0xF100, 1) == 0b11 and bench.leds()["I/O 1"] == "on"
    assert bench.leds()["+24V"] == "on"
    bench.apply("inject_fault", module=1, fault="0x3220")
    bench.run(0.01)
    assert bench.read(0xF100, 1) == 0b01 and bench.leds()["+24V"] == "on"


# What a trainee sees of a TRS-CAT; the instructor's list of injections is the one thing by
# which an injected 0x3220 may differ from the supply really absent (the field volts read 0 V
# either way: a meter on the terminals cannot tell them apart).
_NOT_SEEN = ("injected",)


def _seen(bench: Bench) -> dict:
    snap = {k: v for k, v in bench.trs.snapshot().items() if k not in _NOT_SEEN}
    snap["0xF100:1"] = bench.read(0xF100, 1)
    snap["alarm events"] = [(r["t"], r["code"], r.get("module", 0), r["active"])
                            for r in bench.records("alarm")]
    snap["led events"] = [(r["t"], r["led"], r["pattern"]) for r in bench.records("led")]
    return snap


def _io1_driven(seen: dict) -> list[bool]:
    return [slot["lines"][0]["driving"] for slot in seen["slots"]]


def _supply_cut_and_back(sync_mode: str, cut: tuple[str, dict], back: tuple[str, dict]
                         ) -> tuple[dict, dict]:
    """What is seen with the cause present 10 ms, then 10 ms after it went."""
    bench = Bench(["IO-E", "IO-E"], configured=["IO-E", "IO-E"], sync_mode=sync_mode)
    bench.to_state(AlState.OP)
    for module in (None, 1, 2):
        bench.apply("set_output", module=module, channel=1, value=1)
        bench.apply("set_load", module=module, channel=1, amps=0.25)
    bench.run(0.01)
    bench.clear()
    bench.apply(cut[0], **cut[1])
    bench.run(0.01)
    during = _seen(bench)
    bench.apply(back[0], **back[1])
    bench.run(0.01)
    return during, _seen(bench)


@pytest.mark.parametrize("sync_mode", ["dc", "free_run"])
def test_injected_field_supply_fault_on_the_base_is_the_supply_absent(sync_mode: str) -> None:
    """§10.3: the +24Vdc of the base "viene utilizzata per il driver degli output ed è quella
    che di norma viene erogata verso il bus TRS, per fornire l'alimentazione alle eventuali
    espansioni"; §9.3.7 0x3220 "su base" is that supply failing, so the expansions' outputs go
    unpowered too, as with ``field_supply`` 0 V: outputs, LEDs, 0xF100, alarms, messages and
    the TRS bus current alike; and back when cleared."""
    phys_during, phys_after = _supply_cut_and_back(
        sync_mode, ("field_supply", {"volts": 0.0}), ("field_supply", {"volts": 24.0}))
    inj_during, inj_after = _supply_cut_and_back(
        sync_mode, ("inject_fault", {"fault": "0x3220"}), ("clear_fault", {"fault": "0x3220"}))
    assert _io1_driven(phys_during) == [False] * 3
    assert _io1_driven(inj_during) == [False] * 3
    assert inj_during["trs_bus"]["current_a"] == 0.0
    assert inj_during == phys_during
    assert _io1_driven(inj_after) == [True] * 3
    assert inj_after == phys_after


def test_overcurrent_on_the_trs_bus() -> None:
    """§10.3: at most 8 A along the TRS bus; §9.3.7 0x7100 above it."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    for ch in range(1, 17):
        bench.apply("set_load", channel=ch, amps=0.5)
        bench.apply("set_output", channel=ch, value=1)
    bench.run(0.003)
    assert bench.trs.snapshot()["trs_bus"]["current_a"] == 8.0 and not bench.messages()
    bench.apply("set_load", module=1, channel=1, amps=0.1)
    bench.apply("set_output", module=1, channel=1, value=1)
    bench.run(0.003)
    assert bench.messages()[0]["code"] == "0x7100" and bench.read(0xF100, 4) is False
    assert bench.trs.rail[0].applied == [0] * 16  # bus down: the outputs are off


def test_unplugging_an_expansion_under_power() -> None:
    """§7 forbids it; the TRS bus loses the module: 0x7500, bus shut down."""
    bench = Bench(["IO-E", "AN-E"], configured=["IO-E", "AN-E"])
    bench.to_state(AlState.OP)
    bench.apply("unplug", module=2)
    bench.run(0.002)
    assert bench.messages()[0]["code"] == "0x7500" and bench.read(0xF100, 2) is False
    assert bench.trs.al_state is AlState.OP


def test_expansion_changed_with_power_off_is_a_mismatch() -> None:
    """§9.2: the configuration is read at power-up; the master's list then no longer
    matches."""
    bench = Bench(["IO-E"], master=True, configured=["IO-E"])
    bench.run(1.0)
    assert bench.trs.al_state is AlState.OP
    bench.apply("power", on=False)
    bench.apply("unplug", module=1)
    bench.apply("plug", module=1, type="TRS-AN-E")
    bench.apply("power", on=True)
    bench.run(1.0)
    assert bench.trs.al_state is AlState.PREOP and bench.trs.al_status_code == 0x0070
    assert bench.trs.f050[:3] == [2, 0x494F2D42, 0x414E2D45]


# ---- parsing ---------------------------------------------------------------------------------
@pytest.mark.parametrize(("text", "name"), [
    ("0x3220", "FIELD_SUPPLY"), ("field_supply", "FIELD_SUPPLY"), ("0x6100", "SOFTWARE_ERROR"),
    ("0x5115", "AN_MINUS_12V"), ("0xA000", "CONFIG_ERROR"), ("0x7500", "TRS_COMM_ERROR")])
def test_parse_fault(text: str, name: str) -> None:
    assert parse_fault(text).name == name


@pytest.mark.parametrize(("text", "message"), [
    ("0x7100", "two causes"), ("0x1234", "no code 0x1234"), ("BOGUS", "unknown TRS-CAT fault")])
def test_parse_fault_errors(text: str, message: str) -> None:
    with pytest.raises(CommandError, match=message):
        parse_fault(text)


@pytest.mark.parametrize(("fault", "module", "message"), [
    ("AN_PLUS_12V", None, "no expansion at position 0|TRS-AN-E fault"),
    ("AN_PLUS_12V", 1, "TRS-AN-E fault"),
    ("TRS_COMM_ERROR", 1, "fault of the TRS-CAT itself"),
])
def test_fault_targets(fault: str, module: int | None, message: str) -> None:
    bench = Bench(["IO-E"])
    with pytest.raises(CommandError, match=message):
        bench.apply("inject_fault", module=module, fault=fault)


# ---- 0x10F3 ----------------------------------------------------------------------------------
def _msg(n: int, dtype: DiagType = DiagType.ERROR) -> DiagMessage:
    return DiagMessage(0xE8003220, dtype, 0x3220, n, (n,), f"m{n}")


def test_history_holds_twenty_unacknowledged_messages() -> None:
    """§9.3.7 acknowledge mode, "coda fino a 20 messaggi": a 21st unacknowledged message is
    not stored (it would overwrite one the master has not seen)."""
    hist = DiagHistory()
    assert all(hist.add(_msg(n)) for n in range(MAX_MESSAGES))
    assert (hist.newest, hist.new_available) == (25, True)
    assert not hist.add(_msg(99)) and hist.lost == 1
    hist.acknowledge(10)  # messages in subs 6..10 seen
    assert hist.new_available and hist.newest_ack == 10
    assert hist.add(_msg(100)) and hist.newest == 6  # overwrites the oldest, acknowledged
    assert hist.messages[6].params == (100,)
    hist.acknowledge(6)
    assert not hist.new_available


def test_acknowledging_an_older_message_takes_back_no_acknowledgement() -> None:
    """§9.3.7: 0x10F3:3 is "il messaggio più recente che ha avuto ack", 0x10F3:4 "nuovo
    messaggio disponibile". A master writing an older message's sub after a newer one was
    acknowledged makes no message new again: :3 and :4 stay, and the messages already seen
    may still be overwritten."""
    hist = DiagHistory()
    for n in range(MAX_MESSAGES):
        hist.add(_msg(n))
    hist.acknowledge(25)  # every message seen
    hist.acknowledge(8)
    assert (hist.newest_ack, hist.new_available) == (25, False)
    assert hist.add(_msg(100)) and hist.newest == 6  # the oldest, acknowledged, overwritten
    hist.acknowledge(20)  # older than 6 now: no effect either
    assert (hist.newest_ack, hist.new_available) == (25, True)
    hist.acknowledge(6)
    assert (hist.newest_ack, hist.new_available) == (6, False)


def test_acknowledging_zero_deletes_the_acknowledged_messages() -> None:
    """ETG.1020, acknowledge mode (more in test_trscat_history.py)."""
    hist = DiagHistory()
    hist.add(_msg(1))
    hist.acknowledge(hist.newest)
    hist.acknowledge(0)
    assert (hist.newest, hist.new_available, hist.messages) == (0, False, {})


@pytest.mark.parametrize(("flags", "stored"), [
    (0x00, (True, True, True)), (0x02, (False, True, True)), (0x04, (True, False, True)),
    (0x08, (True, True, False)), (0x0E, (False, False, False))])
def test_flags_disable_message_types(flags: int, stored: tuple[bool, bool, bool]) -> None:
    """§9.3.7 0x10F3:5: Bit1 info, Bit2 warnings, Bit3 errors disabled."""
    hist = DiagHistory()
    hist.set_flags(flags)
    got = tuple(hist.add(_msg(1, t)) for t in (DiagType.INFO, DiagType.WARNING, DiagType.ERROR))
    assert got == stored


def test_message_layout() -> None:
    """ETG.1020 message: Diag Code, Flags (type, local time stamp, 1 parameter), Text ID,
    Time Stamp (ns), then the UNSIGNED8 parameter with its flags 0x0005."""
    raw = DiagMessage(0xE8003220, DiagType.ERROR, 0x3220, 1_500_000_000, (2,), "").encode()
    assert raw == struct.pack("<IHHQHB", 0xE8003220, 0x0112, 0x3220, 1_500_000_000, 5, 2)


def test_history_through_the_object_dictionary() -> None:
    """§9.3.7 table: 0x10F3:2 newest, :3 newest acknowledged (RW), :4 new message (mapped in
    0x1AFF:5, §9.3.4), :5 flags (RW, default 0); messages from sub 6."""
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    assert [bench.read(0x10F3, s) for s in range(1, 6)] == [20, 0, 0, False, 0]
    bench.apply("inject_fault", module=1, fault="AN_PLUS_12V")
    bench.apply("inject_fault", module=1, fault="AN_MINUS_12V")
    bench.run(0.002)
    assert bench.read(0x10F3, 2) == 7 and bench.read(0x10F3, 4) is True
    raw = bench.read(0x10F3, 6)
    assert struct.unpack_from("<IHH", raw) == (0xE8005114, 0x0112, 0x5114)
    assert raw[-3:] == bytes((5, 0, 1))
    bench.apply("acknowledge_messages")
    assert bench.read(0x10F3, 3) == 7 and bench.read(0x10F3, 4) is False
    with pytest.raises(SdoAbort):
        bench.write(0x10F3, 3, 20)  # no message there


def test_messages_are_octet_strings() -> None:
    """ETG.1020, which §9.3.7's 0x10F3 follows (the seed prints no type for the message subs):
    a message is an OCTET_STRING, read as its bytes by the operator and the master's CoE
    upload alike; the Objects tab shows them in hex; a place never written holds no bytes."""
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", module=1, fault="AN_PLUS_12V")
    bench.run(0.002)
    raw = bench.trs.diag.messages[6].encode()
    assert bench.trs.od.entry(0x10F3, 6).dtype is DataType.OCTET_STRING
    assert bench.read(0x10F3, 6) == raw == bench.trs.sdo_upload(0x10F3, 6)
    assert bench.read(0x10F3, 7) == b""
    assert f"<td>{raw.hex(' ').upper()}</td>" in render(read_rows(bench.trs), "10f3:6")


@pytest.mark.parametrize("path", ["operator", "coe_upload", "wire"])
def test_reading_the_newest_message_leaves_new_message_available(path: str) -> None:
    """§9.3.7 acknowledge mode (ETG.1020): :4 stays TRUE whoever reads the newest message;
    only acknowledging it (:3) lowers it."""
    read = {"operator": lambda: bench.read(0x10F3, 6),
            "coe_upload": lambda: bench.trs.sdo_upload(0x10F3, 6),
            "wire": lambda: TrsCatFace().upload_raw(bench.trs, 0x10F3, 6)}[path]
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", fault="FIELD_SUPPLY")
    bench.run(0.002)
    assert bench.read(0x10F3, 2) == 6 and bench.read(0x10F3, 4) is True
    read()
    assert bench.read(0x10F3, 4) is True
    bench.write(0x10F3, 3, 6)
    assert bench.read(0x10F3, 4) is False


def test_emergency_only_with_flag_bit0() -> None:
    """ETG.1020 0x10F3:5 bit 0 (not printed in §9.3.7, default 0): a new message is also sent
    as a CoE emergency: code, error register, byte 0 = slot."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", fault="FIELD_SUPPLY")
    bench.run(0.002)
    assert not bench.records("emergency") and bench.trs.take_emergencies() == []
    bench.apply("clear_fault", fault="FIELD_SUPPLY")
    bench.write(0x10F3, 5, 0x0001)
    bench.run(0.002)
    bench.apply("inject_fault", fault="FIELD_SUPPLY")
    bench.run(0.002)
    [emcy] = bench.records("emergency")
    assert (emcy["code"], emcy["register"], emcy["data"]) == ("0x3220", "0x05", "00 00 00 00 00")
    assert bench.trs.take_emergencies() == [bytes.fromhex("2032050000000000")]


def test_emergency_carries_the_error_register_of_the_moment() -> None:
    """§9.3.7 codes are DS301 emergencies: an EMCY's error register byte is 0x1001 as it
    reads when the error is sent, the bits of every active error, not only the new one's."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(AlState.OP)
    bench.write(0x10F3, 5, 0x0001)
    bench.apply("inject_fault", fault="FIELD_SUPPLY")  # 0x05: generic + voltage
    bench.run(0.002)
    bench.apply("inject_fault", fault="TRS_COMM_ERROR")  # 0x11: generic + communication
    bench.run(0.002)
    assert bench.read(0x1001, 0) == 0x15
    assert [(r["code"], r["register"]) for r in bench.records("emergency")] == [
        ("0x3220", "0x05"), ("0x7500", "0x15")]
    assert bench.trs.take_emergencies() == [bytes.fromhex("2032050000000000"),
                                            bytes.fromhex("0075150000000000")]


def unread_emergency() -> Bench:
    """FIELD_SUPPLY (0x3220) with the cable out: sent as an emergency the master cannot read."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.write(0x10F3, 5, 0x0001)
    bench.apply("link", port="in", connected=False)
    bench.apply("inject_fault", fault="FIELD_SUPPLY")
    bench.run(0.01)
    assert [r["code"] for r in bench.records("emergency")] == ["0x3220"]
    assert bench.trs.take_emergencies() == []
    bench.apply("link", port="in", connected=True)
    return bench


def test_unread_emergencies_are_lost_through_init() -> None:
    """The mailbox stops on the way to INIT and its queue goes (ETG.1000.6, SSC
    MBX_StopMailboxHandler); the 0x10F3 history is an object and keeps the message."""
    bench = unread_emergency()
    stored = bench.read(0x10F3, 2)
    bench.request(AlState.INIT)
    bench.request(AlState.PREOP)
    assert bench.trs.al_state is AlState.PREOP
    assert bench.trs.take_emergencies() == []
    assert bench.read(0x10F3, 2) == stored


def test_unread_emergencies_wait_without_init() -> None:
    bench = unread_emergency()
    assert bench.trs.take_emergencies() == [bytes.fromhex("2032050000000000")]


def test_f100_and_device_txpdo_mapping() -> None:
    """§9.3.4: 0x1AFF = 0xF100:1..4 one to one, plus sub 5 = 0x10F3:4."""
    bench = Bench()
    bench.settle()
    entries = [bench.read(0x1AFF, s) for s in range(6)]
    assert entries == [5, 0xF1000108, 0xF1000201, 0xF1000301, 0xF1000401, 0x10F30401]
    assert bench.read(0xF100, 0) == 4
    assert {Bus.COMMUNICATION, Bus.VOLTAGE, Bus.CURRENT} == {
        f.bus_flag for f in FAULTS.values() if f.bus_flag is not Bus.NONE}
