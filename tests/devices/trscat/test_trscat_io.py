"""Field side of the TRS-CAT: debounce (seed 001 §3), thresholds and protection (§4), field
supply range (§6.2), 8 A on the TRS bus (§10.3), and the I/O seen through the device."""

from __future__ import annotations

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.trscat.catalog import EXPANSIONS, INTEGRATED
from devices.trscat.io import (
    DEBOUNCE_SAMPLES,
    LineBank,
    SlotIo,
    counts_to_volts,
    field_in_range,
    logic_level,
    volts_to_counts,
)


def _sensor(bank: LineBank, line: int, on: bool) -> None:
    bank.set_external(line, 24.0 if on else 0.0)
    bank.drive(0, True)


@pytest.mark.parametrize("pulse", range(1, 7))
def test_debounce_needs_four_samples(pulse: int) -> None:
    """§3: an input is taken when it has stayed in the new state for 4 samples."""
    bank = LineBank(16)
    _sensor(bank, 5, True)
    seen = [bank.sample() for _ in range(pulse)]
    assert seen == [0x20 if n >= DEBOUNCE_SAMPLES else 0 for n in range(1, pulse + 1)]


@pytest.mark.parametrize(("trace", "expected"), [
    ((1, 1, 1, 0, 1, 1, 1, 1), (0, 0, 0, 0, 0, 0, 0, 1)),  # a bounce restarts the count
    ((1, 1, 1, 1, 0, 0, 0, 1), (0, 0, 0, 1, 1, 1, 1, 1)),  # three low samples are not enough
    ((1, 1, 1, 1, 0, 0, 0, 0), (0, 0, 0, 1, 1, 1, 1, 0)),
])
def test_debounce_traces(trace: tuple[int, ...], expected: tuple[int, ...]) -> None:
    """§3, sample by sample on one line, while another line does the opposite (the lines of a
    slot debounce independently)."""
    bank = LineBank(16)
    got = []
    for raw in trace:
        _sensor(bank, 0, bool(raw))
        _sensor(bank, 15, not raw)
        value = bank.sample()
        got.append(value & 1)
    assert tuple(got) == expected
    assert DEBOUNCE_SAMPLES == 4


@pytest.mark.parametrize(("volts", "previous", "level"), [
    (0.0, True, False), (10.0, True, False),  # 0 = 0..10 V
    (14.0, False, True), (24.0, False, True), (30.0, False, True),  # 1 = 14..24 V
    (12.0, False, False), (12.0, True, True),  # undefined band: the level stays
])
def test_input_thresholds(volts: float, previous: bool, level: bool) -> None:
    """§4 "Livelli di soglia Input"."""
    assert logic_level(volts, previous) is level


@pytest.mark.parametrize(("volts", "ok"), [
    (0.0, False), (17.9, False), (18.0, True), (24.0, True), (30.0, True), (30.1, False)])
def test_field_supply_range(volts: float, ok: bool) -> None:
    """§6.2 VO Output Power Supply 18..30 V; §8.4 the LED is off out of range."""
    assert field_in_range(volts) is ok


@pytest.mark.parametrize(("load", "driving", "tripped"), [
    (0.0, True, False), (0.5, True, False), (0.51, False, True), (50.0, False, True)])
def test_output_protection(load: float, driving: bool, tripped: bool) -> None:
    """§4: 0.5 A per output, protected against short circuit and overload."""
    bank = LineBank(16)
    bank.set_load(2, load)
    bank.drive(0b100, True)
    assert (bool(bank.driving), bool(bank.tripped)) == (driving, tripped)
    assert bool(bank.level) is driving  # a tripped output leaves the line to the field (0 V)
    assert bank.current_a == (load if driving else 0.0)


def test_output_protection_acts_on_the_load_at_once() -> None:
    """§4: the protection is the high-side driver's own, so it acts on the load, not on the
    next drive: a short on an output that is on switches it off at once, and the output comes
    back by itself once the load is within 0.5 A again (no reset command in §9.3)."""
    bank = LineBank(16)
    bank.drive(0b101, True)
    bank.set_load(2, 3.0)
    assert (bank.driving, bank.tripped, bank.level) == (0b001, 0b100, 0b001)
    assert bank.current_a == 0.0
    bank.set_load(2, 0.4)
    assert (bank.driving, bank.tripped, bank.level) == (0b101, 0, 0b101)
    assert bank.current_a == 0.4
    bank.drive(0, True)
    bank.set_load(0, 9.0)  # an output that is off does not trip
    assert (bank.driving, bank.tripped) == (0, 0)


def test_output_needs_the_field_supply() -> None:
    """§3: the field supply is required to switch the outputs on."""
    bank = LineBank(16)
    bank.drive(0xFFFF, False)
    assert bank.driving == 0 and bank.level == 0


def test_undefined_band_keeps_the_level() -> None:
    """§4: a sensor at 12 V after the output was on: the line stays at 1."""
    bank = LineBank(16)
    bank.set_external(0, 12.0)
    bank.drive(1, True)
    bank.drive(0, True)
    assert bank.level == 1
    bank.set_external(0, 9.0)
    bank.drive(0, True)
    assert bank.level == 0


def test_bidirectional_line_reads_its_own_output() -> None:
    """§3: input n and output n are one terminal; an output on reads back as 1."""
    io = SlotIo.new(INTEGRATED)
    outputs = [1] + [0] * 15
    for _ in range(DEBOUNCE_SAMPLES):
        io.cycle(outputs, 24.0, working=True)
    assert io.inputs[0] == 1 and io.inputs[1] == 0


def test_bus_down_sends_zero_and_drives_nothing() -> None:
    io = SlotIo.new(INTEGRATED)
    assert io.lines is not None
    io.lines.set_external(0, 24.0)
    for _ in range(DEBOUNCE_SAMPLES):
        io.cycle([1] * 16, 24.0, working=False)
    assert io.applied == [0] * 16 and io.inputs == [0] * 16
    assert io.lines.level == 1  # the sensor still drives the terminal (its LED shows it)


@pytest.mark.parametrize(("volts", "counts"), [
    (0.0, 0), (10.0, 0x7FFF), (-10.0, -0x7FFF), (5.0, 16384), (12.0, 0x7FFF)])
def test_analog_scaling(volts: float, counts: int) -> None:
    """FieldRig: AN-E channels are +-10 V on INT16 (docs/trscat.md)."""
    assert volts_to_counts(volts) == counts
    assert counts_to_volts(0x7FFF) == 10.0


# ---- through the device ----------------------------------------------------------------------
def test_input_latency_is_four_dc_cycles() -> None:
    """§3 + §9.1.1: in DC-SYNC one sample per SYNC0 (1 ms here), so 4 ms to see an input."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.run(0.01)
    bench.apply("set_input", channel=3, on=True)
    seen = []
    for _ in range(6):
        bench.step()
        seen.append(bench.read(0x6000, 3))
    assert seen == [0, 0, 0, 1, 1, 1]


def test_input_latency_is_four_free_run_cycles() -> None:
    """§9.1.1 FREE-RUN: 500 us local cycle, so 2 ms (two 1 ms steps) to see an input."""
    bench = Bench(sync_mode="free_run")
    bench.to_state(AlState.OP)
    bench.apply("set_input", channel=1, on=True)
    bench.step()
    assert bench.read(0x6000, 1) == 0
    bench.step()
    assert bench.read(0x6000, 1) == 1


def test_yellow_led_follows_the_line() -> None:
    """§8.3: the I/O LED is on while the logic state is 1 (input or output)."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("set_input", channel=16, on=True)
    bench.apply("set_output", channel=2, value=1)
    bench.run(0.005)
    leds = bench.leds()
    assert leds["I/O 16"] == "on" and leds["I/O 2"] == "on" and leds["I/O 1"] == "off"


def test_yellow_led_follows_a_sensor_without_a_local_cycle() -> None:
    """§8.3: the LED shows the logic state of the terminal, which is the sensor's voltage
    (§4 thresholds), local cycle or not. With SYNC0 lost (DC-SYNC: no local cycle, §9.1.1) a
    sensor switched on lights its LED at once; only the sampled input (0x6000, the §3
    debounce) waits for a local cycle. It used to stay dark until SYNC0 came back."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("lose_sync0", lost=True)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP  # the fatal sync error (0x002C)
    bench.apply("set_input", channel=1, on=True)
    bench.apply("set_input_voltage", channel=2, volts=12.0)  # undefined band: stays 0
    bench.step()
    assert bench.leds()["I/O 1"] == "on" and bench.leds()["I/O 2"] == "off"
    assert bench.trs.snapshot()["slots"][0]["lines"][0]["level"] is True
    assert bench.read(0x6000, 1) == 0  # no sample without a local cycle
    bench.apply("set_input", channel=1, on=False)
    bench.step()
    assert bench.leds()["I/O 1"] == "off"


def test_output_protection_trips_without_a_local_cycle() -> None:
    """§4 "Protezione degli Output contro: cortocircuito, sovraccarico": the driver's own
    protection, local cycle or not. With SYNC0 lost (DC-SYNC: no local cycle, §9.1.1) the
    fall on the fatal sync error holds the outputs (§9.3.5, 0xF701 = 0): a short on a held
    output switches that output off at once (LED off, nothing drawn), and the TRS bus stays up.
    The output used to keep driving it, and a 20 A short was counted on the TRS bus: 0x7100
    overcurrent, the whole bus shut down until power-off."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("set_output", channel=1, value=1)
    bench.run(0.01)
    bench.apply("lose_sync0", lost=True)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP and bench.leds()["I/O 1"] == "on"
    bench.apply("set_load", channel=1, amps=2.0)
    bench.step()
    line = bench.trs.snapshot()["slots"][0]["lines"][0]
    assert (line["driving"], line["tripped"]) == (False, True)
    assert bench.leds()["I/O 1"] == "off"
    bench.apply("set_load", channel=1, amps=20.0)
    bench.run(0.01)
    assert bench.trs.snapshot()["trs_bus"]["state"] == "running"
    assert not bench.records("alarm")
    bench.apply("set_load", channel=1, amps=0.2)  # the short removed: the output is back
    bench.step()
    line = bench.trs.snapshot()["slots"][0]["lines"][0]
    assert (line["driving"], line["tripped"]) == (True, False)
    assert bench.leds()["I/O 1"] == "on"


def test_outputs_only_in_op() -> None:
    """§9.2: in SAFE-OP the outputs stay in the safe state; OP applies the master's."""
    bench = Bench()
    bench.to_state(AlState.SAFEOP)
    bench.apply("set_output", channel=1, value=1)
    bench.run(0.005)
    assert bench.trs.rail[0].applied[0] == 0
    bench.request(AlState.OP)
    bench.run(0.005)
    assert bench.trs.rail[0].applied[0] == 1
    bench.request(AlState.SAFEOP)
    bench.run(0.005)
    assert bench.trs.rail[0].applied[0] == 0


def test_analog_and_word_channels() -> None:
    bench = Bench(["AN-E", "XX-E"], configured=["AN-E", "XX-E"])
    bench.to_state(AlState.OP)
    bench.apply("set_analog_input", module=1, channel=2, volts=-5.0)
    bench.apply("set_input_word", module=2, channel=1, value=0xBEEF)
    bench.apply("set_output", module=1, channel=1, value=-1000)
    bench.run(0.003)
    assert bench.read(0x6010, 2) == volts_to_counts(-5.0)
    assert bench.read(0x6020, 1) == 0xBEEF
    assert bench.trs.rail[1].applied == [-1000, 0]
    assert EXPANSIONS["TRS-AN-E"].inputs == 4


@pytest.mark.parametrize(("action", "module", "args", "message"), [
    ("set_analog_input", 1, {"channel": 1, "volts": 1.0}, "has no analog channels"),
    ("set_input", 1, {"channel": 1, "on": True}, "has no digital channels"),
    ("set_input", 3, {"channel": 1, "on": True}, "no expansion at position 3"),
    ("set_input_word", 2, {"channel": 2, "value": 1}, "channel 2 outside 1..1"),
    ("set_output", None, {"channel": 1, "value": 2}, "outside 0..1"),
])
def test_channel_errors(action: str, module: int | None, args: dict, message: str) -> None:
    from devices.device import CommandError
    bench = Bench(["KK-E", "XX-E"])
    bench.settle()
    with pytest.raises(CommandError, match=message):
        bench.apply(action, module=module, **args)
