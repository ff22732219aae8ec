"""The CPX-E-EC's LEDs (seed 002 §2.1.6, §2.4.1 Tab. 11-13), each row driven by its cause."""

from __future__ import annotations

import pytest
from cpx_bench import Bench, tab9

from devices.cpx.leds import (
    ERROR_PRIORITY,
    ERROR_TABLE,
    LINK_TABLE,
    RUN_TABLE,
    Colour,
    ErrorShows,
    LedState,
    LinkShows,
    RunShows,
    channels,
)
from devices.ethercat import AlState
from devices.leds import LedPattern

P = LedPattern

# Tab. 11 as printed: (shows, pattern, colour).
TAB11 = [(RunShows.OP, P.ON, Colour.GREEN), (RunShows.PREOP, P.BLINKING, Colour.GREEN),
         (RunShows.SAFEOP, P.SINGLE_FLASH, Colour.GREEN),
         (RunShows.BOOT, P.FLICKERING, Colour.GREEN),
         (RunShows.BOOTLOADER, P.ON, Colour.ORANGE), (RunShows.INIT, P.OFF, Colour.GREEN)]
# Tab. 12 as printed.
TAB12 = [(ErrorShows.AC_FAILURE, P.ON, Colour.RED),
         (ErrorShows.INVALID_CONFIGURATION, P.BLINKING, Colour.RED),
         (ErrorShows.SYNC_ERROR, P.SINGLE_FLASH, Colour.RED),
         (ErrorShows.WATCHDOG, P.DOUBLE_FLASH, Colour.RED),
         (ErrorShows.RESERVED, P.TRIPLE_FLASH, Colour.RED),
         (ErrorShows.BOOTING_ERROR, P.FLICKERING, Colour.RED),
         (ErrorShows.BOOTLOADER, P.ON, Colour.ORANGE), (ErrorShows.NONE, P.OFF, Colour.RED)]
# Tab. 13.
TAB13 = [(LinkShows.LINK, P.ON), (LinkShows.TRAFFIC, P.FLICKERING), (LinkShows.NO_LINK, P.OFF)]


@pytest.mark.parametrize(("shows", "pattern", "colour"), TAB11)
def test_tab11(shows: RunShows, pattern: LedPattern, colour: Colour) -> None:
    assert RUN_TABLE[shows] == LedState(pattern, colour)


@pytest.mark.parametrize(("shows", "pattern", "colour"), TAB12)
def test_tab12(shows: ErrorShows, pattern: LedPattern, colour: Colour) -> None:
    assert ERROR_TABLE[shows] == LedState(pattern, colour)


@pytest.mark.parametrize(("shows", "pattern"), TAB13)
def test_tab13(shows: LinkShows, pattern: LedPattern) -> None:
    assert LINK_TABLE[shows] == LedState(pattern, Colour.GREEN)


def test_triple_flash_is_reserved() -> None:
    """Tab. 12: "зарезервировано" - no cause of the model shows it."""
    assert ErrorShows.RESERVED not in ERROR_PRIORITY


def test_orange_is_a_channel_of_its_own() -> None:
    assert channels("Run", LedState(P.ON, Colour.ORANGE)) == {"Run": P.OFF, "Run.orange": P.ON}
    assert channels("Run", LedState(P.BLINKING, Colour.GREEN)) == {
        "Run": P.BLINKING, "Run.orange": P.OFF}
    assert channels("PS", LedState(P.ON, Colour.GREEN)) == {"PS": P.ON}


@pytest.mark.parametrize(("state", "pattern"), [
    (AlState.INIT, "off"), (AlState.PREOP, "blinking"), (AlState.SAFEOP, "single_flash"),
    (AlState.OP, "on"), (AlState.BOOT, "flickering")])
def test_run_follows_the_esm(state: AlState, pattern: str) -> None:
    """Tab. 11, driven by AL control requests as a master makes them."""
    bench = Bench(master=False)
    path = {AlState.INIT: [], AlState.PREOP: [AlState.PREOP], AlState.BOOT: [AlState.BOOT],
            AlState.SAFEOP: [AlState.PREOP, AlState.SAFEOP],
            AlState.OP: [AlState.PREOP, AlState.SAFEOP, AlState.OP]}[state]
    for target in path:
        bench.cpx.request_state(target)
        bench.cpx.exchange_frame(bench.now)
    assert bench.cpx.al_state is state
    assert bench.led_state("Run") == (pattern, "green")


def test_error_off_in_op_and_leds_change_only_on_change() -> None:
    bench = tab9().to_op()
    bench.run(0.2)
    assert bench.led_state("Error") == ("off", "red")
    since = len(bench.events)
    bench.run(1.0)
    assert bench.records("led", since) == []


def test_error_on_application_controller_failure() -> None:
    bench = tab9().to_op()
    bench.apply("inject_fault", fault="ac_failure")
    bench.run(0.01)
    assert bench.led_state("Error") == ("on", "red")
    bench.apply("clear_fault", fault="ac_failure")  # the controller restarts
    bench.to_op()
    assert bench.led_state("Error") == ("off", "red")


@pytest.mark.parametrize("cause", ["cable", "no master", "refused"])
def test_error_blinking_invalid_configuration_or_no_link(cause: str) -> None:
    """Tab. 12 blinking: cable / connection broken, no master, master inactive, invalid
    configuration."""
    if cause == "cable":
        bench = tab9().to_op()
        bench.apply("cable", port="in", connected=False)
        bench.run(0.01)
        assert bench.led("LA IN") == "off"
    elif cause == "no master":
        bench = tab9(master=False)
        bench.run(0.2)
    else:
        bench = tab9(master=False)
        bench.apply("inject_fault", fault="sm_invalid_size", sm=3)
        bench.cpx.request_state(AlState.PREOP)
        bench.cpx.request_state(AlState.SAFEOP)
        bench.cpx.exchange_frame(bench.now)
        bench.step()
        bench.cpx.exchange_frame(bench.now)
    assert bench.led_state("Error") == ("blinking", "red")


def test_error_single_flash_on_sync_error() -> None:
    """Tab. 12: unsolicited OP -> SAFEOP because of a sync error."""
    bench = tab9().to_op()
    bench.apply("inject_fault", fault="sync_error")
    bench.run_until(lambda: bench.cpx.al_state is AlState.SAFEOP, 1.0)
    assert (bench.cpx.al_status, bench.cpx.al_status_code) == (0x14, 0x001A)
    assert bench.led_state("Error") == ("single_flash", "red")


def test_error_double_flash_on_watchdog() -> None:
    """Tab. 12: Sync Manager watchdog, 100 ms without process data."""
    bench = tab9().to_op()
    bench.apply("inject_fault", fault="watchdog")
    start = bench.now
    bench.run_until(lambda: bench.cpx.al_state is AlState.SAFEOP, 1.0)
    assert 100_000 < bench.now - start <= 102_000
    assert bench.cpx.al_status_code == 0x001B
    assert bench.led_state("Error") == ("double_flash", "red")


def test_error_flickering_on_booting_error() -> None:
    """Tab. 12: flash checksum of the application controller, found at the next start."""
    bench = tab9().to_op()
    bench.apply("inject_fault", fault="booting_error")
    bench.run(0.05)
    assert bench.led_state("Error") == ("off", "red")
    bench.apply("restart")
    bench.run(0.5)
    assert bench.led_state("Error") == ("flickering", "red")
    assert bench.cpx.al_state is AlState.INIT and bench.cpx.al_status_code == 0x0014


@pytest.mark.parametrize("start", ["restart", "power cycle"])
def test_a_booting_error_is_init_with_the_error_flag_before_any_request(start: str) -> None:
    """Tab. 12 flickering «Ошибка загрузки (Booting Error)» is ETG.1300's row: "INIT state
    reached, but the Error Indicator bit is set in the AL Status register". The bus module
    starts in INIT + error (0x0014 "No valid firmware") on its own, so a master's scan reads
    it before it asks for anything; a request for PREOP is refused again, the LED the same."""
    bench = Bench(master=False)
    bench.apply("inject_fault", fault="booting_error")
    if start == "restart":
        bench.apply("restart")
    else:
        bench.apply("power", on=False)
        bench.run(0.05)
        bench.apply("power", on=True)
    bench.step()
    cpx = bench.cpx
    assert (cpx.al_state, cpx.al_status, cpx.al_status_code) == (AlState.INIT, 0x11, 0x0014)
    assert bench.led_state("Error") == ("flickering", "red")
    cpx.request_state(AlState.PREOP, ack=True)
    bench.step()
    assert (cpx.al_state, cpx.al_status, cpx.al_status_code) == (AlState.INIT, 0x11, 0x0014)
    assert bench.led_state("Error") == ("flickering", "red")
    bench.apply("clear_fault", fault="booting_error")
    bench.apply("restart")
    bench.step()
    assert (cpx.al_state, cpx.al_status, cpx.al_status_code) == (AlState.INIT, 0x01, 0x0000)


def test_bootloader_mode_starts_without_the_error_flag() -> None:
    """Tab. 6 on / on is a mode the technician chose, not an error: INIT without the flag
    until a request for PREOP is refused (Tab. 11 / 12 orange, choice 44)."""
    bench = Bench(master=False, dil1=True, dil2=True)
    bench.step()
    cpx = bench.cpx
    assert (cpx.al_state, cpx.al_status, cpx.al_status_code) == (AlState.INIT, 0x01, 0x0000)
    assert bench.led_state("Error") == ("on", "orange")


def test_la_in_and_la_out() -> None:
    """Tab. 13: on = link, flickering = traffic, off = no link."""
    bench = tab9(master=False, out_connected=True)
    bench.step()
    assert (bench.led("LA IN"), bench.led("LA OUT")) == ("on", "on")
    bench.cpx.exchange_frame(bench.now)
    bench.step()
    assert (bench.led("LA IN"), bench.led("LA OUT")) == ("flickering", "flickering")
    bench.run(0.1)
    assert bench.led("LA IN") == "on"
    bench.apply("cable", port="out", connected=False)
    assert bench.led("LA OUT") == "off"


def test_system_leds() -> None:
    """§2.1.6: PS (U_EL/SEN), PL (U_OUT), SF (system fault), M (forcing)."""
    bench = tab9().to_op()
    assert [bench.led(n) for n in ("PS", "PL", "SF", "M")] == ["on", "on", "off", "off"]
    bench.apply("supply", el_sen=17.0, out=15.0)
    bench.run(0.01)
    assert (bench.led("PS"), bench.led("PL")) == ("blinking", "blinking")
    assert bench.led("SF") == "double_flash"  # undervoltage: class 2
    bench.apply("supply", el_sen=24.0, out=0.0)
    bench.run(0.01)
    assert (bench.led("PS"), bench.led("PL")) == ("on", "off")
    bench.apply("supply", out=24.0)
    bench.apply("inject_fault", module=1, fault="module_failure")
    bench.run(0.01)
    assert bench.led("SF") == "triple_flash"  # CPX error > 128: class 3
    bench.apply("force", module=2, channel=0, value=1)
    bench.run(0.01)
    assert bench.led("M") == "on"
    assert bench.cpx.modules[1].driven[0] == 1
    bench.apply("force", module=2, channel=0)
    bench.run(0.01)
    assert bench.led("M") == "off"


def test_power_off_darkens_everything_after_20_ms() -> None:
    """Tab. 29: 20 ms bridging of a supply failure."""
    bench = tab9().to_op()
    bench.apply("power", on=False)
    bench.run(0.019)
    assert bench.cpx.powered and bench.led("Run") == "on"
    bench.run(0.002)
    assert not bench.cpx.powered
    assert set(bench.cpx.snapshot()["leds"].values()) == {"off"}


def test_a_short_dip_is_bridged() -> None:
    bench = tab9().to_op()
    bench.apply("supply", el_sen=0.0)
    bench.run(0.015)
    bench.apply("supply", el_sen=24.0)
    bench.run(0.1)
    assert bench.cpx.powered and bench.cpx.al_state is AlState.OP


def _error_led(bench: Bench, module: int) -> dict[str, object]:
    led: dict[str, object] = bench.cpx.snapshot()["modules"][module - 1]["error_led"]
    return led


def test_module_error_led_shows_the_worst_diagnosed_cause() -> None:
    """A module's red LED (§2.4.1 refers its patterns to the CPX-E system description;
    docs/cpx-e-ec.md choice 30): on while the bus module diagnoses a cause on the module, and
    the model says which one it shows — the worst of those diagnosed (failure, sensor-supply
    short, output short, wire break, U_OUT low) — and on which channels. The view only words
    it; before, the dashboard ranked the causes itself."""
    bench = Bench(["16DI", "8DO", ("4AI-U-I", {"ranges": "4-20mA"})], seed=3).to_op()
    dark = {"pattern": "off", "colour": "red", "cause": None, "channels": []}
    assert [_error_led(bench, m) for m in (1, 2, 3)] == [dark] * 3
    bench.apply("wire_break", module=3, channel=2, on=True)
    bench.apply("wire_break", module=3, channel=0, on=True)
    bench.run(0.01)
    assert _error_led(bench, 3) == {"pattern": "on", "colour": "red", "cause": "wire_break",
                                    "channels": [0, 2]}
    bench.apply("short_circuit", module=3, on=True)  # the sensor supply: worse, no channel
    bench.run(0.01)
    assert _error_led(bench, 3) == {"pattern": "on", "colour": "red",
                                    "cause": "short_circuit_sensor_supply", "channels": []}
    bench.apply("inject_fault", module=3, fault="module_failure")
    bench.run(0.01)
    assert _error_led(bench, 3)["cause"] == "module_failure"
    for channel in (5, 3):
        bench.apply("short_circuit", module=2, channel=channel, on=True)
        bench.apply("write_object", index=0x7002, sub=channel + 1, value=1)
    bench.run(0.01)
    assert _error_led(bench, 2) == {"pattern": "on", "colour": "red",
                                    "cause": "short_circuit_outputs", "channels": [3, 5]}
    # U_OUT low: the outputs are not energised, their shorts draw no current and go; U_OUT
    # low is what the module diagnoses and shows (choice 30)
    bench.apply("supply", out=15.0)
    bench.run(0.01)
    causes = {d["cause"] for d in bench.cpx.snapshot()["modules"][1]["diagnosed"]}
    assert causes == {"undervoltage_out"}
    assert _error_led(bench, 2) == {"pattern": "on", "colour": "red",
                                    "cause": "undervoltage_out", "channels": []}
    bench.apply("supply", out=24.0)
    bench.run(0.01)
    assert _error_led(bench, 2)["channels"] == [3, 5]
    for channel in (5, 3):
        bench.apply("short_circuit", module=2, channel=channel, on=False)
    bench.run(0.01)
    assert _error_led(bench, 2) == dark
    assert _error_led(bench, 1) == dark
