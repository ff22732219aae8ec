"""CNF procedure, internal-bus scan and the stored configuration (seed 000 §2, §3, §7.5)."""

from __future__ import annotations

import json

import pytest
from fastcat_bench import THREE, US, Bench, scan_us

from devices.ethercat import AlState
from devices.fastcat.cnf import (
    CNF_MIN_HOLD_US,
    CNF_RESET_US,
    FLASH_WRITE_US,
    SCAN_PER_MODULE_US,
    SCAN_SETUP_US,
    BusScan,
    CnfButton,
    ScanPhase,
)
from devices.flash import MemoryFlash


def stored(names: list[str]) -> MemoryFlash:
    return MemoryFlash(json.dumps(names).encode())


# ---- the timeline as data -------------------------------------------------------------------
def test_minimum_hold_is_three_seconds() -> None:
    """§2: "mantenere premuto il pulsante CNF per almeno tre secondi"."""
    assert CNF_MIN_HOLD_US == 3 * US
    assert not CnfButton.long_enough(2_999_999)
    assert CnfButton.long_enough(3_000_000)


def test_scan_time_grows_with_the_module_count() -> None:
    """§3: the scan takes "qualche secondo", depending on the number of modules."""
    lengths = [BusScan(0, tuple(range(1, n + 1))).end_us for n in (0, 1, 8, 16)]
    assert lengths == [scan_us(n) for n in (0, 1, 8, 16)]
    assert lengths == sorted(lengths) and lengths[-1] <= 6 * US


def test_cnf_scan_phases() -> None:
    scan = BusScan(1000, (1, 2, 3), cnf=True)
    t_scan = 1000 + CNF_RESET_US
    t_stored = t_scan + SCAN_SETUP_US + 4 * SCAN_PER_MODULE_US
    assert scan.phase(1000) is ScanPhase.RESETTING
    assert scan.phase(t_scan) is ScanPhase.SCANNING
    assert scan.phase(t_stored) is ScanPhase.STORING
    assert scan.phase(t_stored + FLASH_WRITE_US) is ScanPhase.IDLE
    recognised = [scan.recognised(t_scan + SCAN_SETUP_US + k * SCAN_PER_MODULE_US - d)
                  for k in (1, 2, 3) for d in (1, 0)]
    assert recognised == [0, 1, 1, 2, 2, 3]  # one at a time, every 250 ms


def test_timed_hold_counts_to_its_scheduled_instant() -> None:
    button = CnfButton()
    button.press(1000, hold_us=3 * US)
    assert not button.release_due(3 * US)
    assert button.release_due(3 * US + 1000)
    assert button.release(3 * US + 5000) == 3 * US


def test_timed_press_while_down_counts_from_the_first_press() -> None:
    """A timed press on a button already down keeps it down ``hold`` more seconds; the hold
    runs from when it went down (§2 counts how long the button was kept down)."""
    button = CnfButton()
    button.press(0)
    button.press(5 * US, hold_us=1 * US)
    assert not button.release_due(6 * US - 1)
    assert button.release_due(6 * US)
    assert button.release(6 * US) == 6 * US


def test_second_timed_press_does_not_shorten_the_first() -> None:
    """The button comes up when the last timed press ends, not the latest one given."""
    button = CnfButton()
    button.press(0, hold_us=3_500_000)
    button.press(500_000, hold_us=1 * US)
    assert not button.release_due(3_500_000 - 1)
    assert button.release(3_500_000) == 3_500_000
    button.press(10 * US, hold_us=1 * US)
    button.press(10_500_000, hold_us=1 * US)  # ends later than the first: it extends it
    assert button.release(12 * US) == 1_500_000


# ---- on the coupler ---------------------------------------------------------------------------
def test_factory_new_coupler_accepts_its_modules_and_stores_nothing() -> None:
    """No configuration in flash: nothing to compare; only CNF stores (docs)."""
    bench = Bench()
    bench.settle()
    assert bench.fc.alarm is None
    assert bench.flash.writes == 0 and bench.fc.snapshot()["stored_config"] is None
    assert bench.fc.snapshot()["detected"] == list(THREE)


def test_press_shorter_than_three_seconds_does_nothing() -> None:
    """§2: only a press of at least 3 s starts the procedure."""
    bench = Bench()
    bench.to_state(AlState.OP)
    mark = bench.mark()
    bench.apply("hold_cnf", seconds=2.9)
    bench.run(4.0)
    kinds = {(r["event"], r.get("machine")) for r in bench.records(since=mark)}
    assert kinds == {("state", "cnf_button")}
    assert bench.fc.al_state is AlState.OP and bench.flash.writes == 0


def test_held_seconds_shown_while_pressed() -> None:
    """The UI's progress bar toward 3 s reads cnf.held_s."""
    bench = Bench()
    bench.settle()
    bench.apply("press_cnf")
    bench.run(1.5)
    cnf = bench.fc.snapshot()["cnf"]
    assert cnf["pressed"] and cnf["held_s"] == pytest.approx(1.5)
    bench.apply("release_cnf")
    assert bench.fc.snapshot()["cnf"] == {"pressed": False, "held_s": 0.0, "phase": "idle"}
    assert bench.flash.writes == 0


def test_three_second_press_runs_the_hardware_configuration() -> None:
    """§2: reset, sequential scan with red LEDs one by one, then yellow blink + store."""
    bench = Bench()
    bench.to_state(AlState.OP)
    mark = bench.mark()
    t0 = bench.now
    bench.apply("hold_cnf", seconds=3.0)
    bench.run_until(lambda: bench.fc.snapshot()["cnf"]["phase"] == "idle"
                    and bench.now > t0 + 3 * US)
    release = t0 + 3 * US
    phases = [(r["t"], r["to"]) for r in bench.records("state", mark)
              if r.get("machine") == "cnf"]
    scanning = release + CNF_RESET_US
    storing = scanning + SCAN_SETUP_US + 4 * SCAN_PER_MODULE_US
    assert phases == [(release / US, "resetting"), (scanning / US, "scanning"),
                      (storing / US, "storing"), ((storing + FLASH_WRITE_US) / US, "idle")]
    # The ESM falls to INIT at the release (docs: the procedure is a local INIT).
    state = [(r["t"], r["from"], r["to"]) for r in bench.records("state", mark)
             if not r.get("machine")]
    assert state == [(release / US, "OP", "INIT")]
    leds = bench.led_events(mark)
    reds_on = [(t, name) for t, name, p in leds if name.endswith(".red") and p == "on"]
    first = scanning + SCAN_SETUP_US + SCAN_PER_MODULE_US
    assert reds_on == [((first + k * SCAN_PER_MODULE_US) / US, f"{k + 1}.red") for k in range(3)]
    yellow = [(t, name) for t, name, p in leds if name.endswith(".yellow") and p == "blinking"]
    assert yellow == [(storing / US, f"{k}.yellow") for k in (1, 2, 3)]
    assert all(t <= release / US for t, name, p in leds
               if name.endswith(".yellow") and p == "off")  # dark from the reset on
    assert bench.flash.writes == 1
    assert json.loads(bench.flash.data) == list(THREE)
    assert bench.fc.snapshot()["stored_config"] == list(THREE)


def test_stored_configuration_survives_a_new_coupler() -> None:
    """The flash outlives the model: a new FastCat on the same store compares against it."""
    bench = Bench()
    bench.settle()
    bench.apply("hold_cnf", seconds=3.0)
    bench.run(8.0)
    assert bench.flash.writes == 1
    again = Bench(flash=bench.flash)
    again.settle()
    assert again.fc.snapshot()["stored_config"] == list(THREE)
    assert again.fc.alarm is None and again.flash.writes == 1


def test_mismatch_at_power_up() -> None:
    """§2: stored config differs -> coupler ERR blinking, module reds steady, alarm 0x01;
    PREOP -> SAFEOP refused with 0x0052 (docs)."""
    bench = Bench(("DB16", "AI8C", "AI8D"), flash=stored(list(THREE)))
    bench.settle()
    assert bench.fc.alarm is not None
    assert (bench.fc.alarm.code, bench.fc.alarm.module) == (0x01, 2)
    assert bench.emergencies() == ["02 00 00 01 00"]
    leds = bench.fc.snapshot()["leds"]
    assert leds["ERR"] == "blinking"
    assert [leds[f"{k}.red"] for k in (1, 2, 3)] == ["on"] * 3
    assert [leds[f"{k}.yellow"] for k in (1, 2, 3)] == ["off"] * 3
    # The reds lit by the scan stay on: no off event between the scan and the alarm.
    reds = [(name, p) for _t, name, p in bench.led_events() if name.endswith(".red")]
    assert reds == [("1.red", "on"), ("2.red", "on"), ("3.red", "on")]
    bench.fc.request_state(AlState.PREOP)
    bench.fc.request_state(AlState.SAFEOP)
    assert bench.fc.al_state is AlState.PREOP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x12, 0x0052)


def test_stored_module_missing_at_power_up_is_module_no_pres() -> None:
    """§7.5 0x02: the stored module at the end of the bus is not there."""
    bench = Bench(("DB16", "AI8D"), flash=stored(list(THREE)))
    bench.settle()
    assert bench.emergencies() == ["03 00 00 02 00"]


def test_extra_module_at_power_up_is_module_changed() -> None:
    bench = Bench((*THREE, "DI16"), flash=stored(list(THREE)))
    bench.settle()
    assert bench.emergencies() == ["04 00 00 01 00"]


def test_cnf_accepts_the_new_configuration_and_clears_the_mismatch() -> None:
    """§7.7 0x0052 asks for "an hardware configuration procedure": that is CNF."""
    bench = Bench(("DB16", "AI8C", "AI8D"), flash=stored(list(THREE)))
    bench.settle()
    bench.apply("hold_cnf", seconds=3.5)
    bench.run(8.0)
    assert bench.fc.alarm is None
    assert bench.fc.snapshot()["stored_config"] == ["DB16", "AI8C", "AI8D"]
    assert bench.fc.snapshot()["leds"]["ERR"] == "off"
    bench.to_state(AlState.OP)


def test_flash_write_failure_raises_save_flash() -> None:
    """§7.5 0x11 SAVE_FLASH when the store cannot be written; a one-shot cause (docs)."""
    flash = MemoryFlash(fail=True)
    bench = Bench(flash=flash)
    bench.settle()
    bench.apply("hold_cnf", seconds=3.0)
    bench.run(8.0)
    assert bench.emergencies() == ["00 00 00 11 00"]
    assert bench.fc.snapshot()["stored_config"] is None
    bench.reset_fault()
    assert bench.fc.alarm is None


def test_cnf_while_unpowered_does_nothing() -> None:
    bench = Bench()
    bench.settle()
    bench.apply("power", on=False)
    mark = bench.mark()
    bench.apply("hold_cnf", seconds=3.0)
    bench.run(5.0)
    assert bench.records(since=mark) == [] and bench.flash.writes == 0


def test_power_off_while_held_releases_the_button_with_its_event() -> None:
    """A dead coupler does not read its button: the hold is void and the snapshot says
    released. The event log said so too little: a ``pressed`` never followed by ``released``
    (the recording and the Event log showed CNF held for good). No procedure runs, however
    long it was held, and nothing is stored."""
    bench = Bench()
    bench.settle()
    mark = bench.mark()
    bench.apply("press_cnf")
    bench.run(3.5)
    bench.apply("power", on=False)
    bench.run(0.1)
    buttons = [(r["from"], r["to"]) for r in bench.records("state", mark)
               if r.get("machine") == "cnf_button"]
    assert buttons == [("released", "pressed"), ("pressed", "released")]
    assert bench.fc.snapshot()["cnf"]["pressed"] is False
    assert [r for r in bench.records("state", mark) if r.get("machine") == "cnf"] == []
    after = bench.mark()
    bench.apply("release_cnf")  # the Hold CNF box unticked afterwards: nothing more
    assert bench.records(since=after) == [] and bench.flash.writes == 0


def test_return_to_init_rescans_and_preop_waits_for_it() -> None:
    """§3: a scan on every return to INIT; INIT -> PREOP completes when it is done."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.fc.request_state(AlState.INIT)
    t0 = bench.now
    bench.fc.request_state(AlState.PREOP)
    assert bench.fc.al_state is AlState.INIT and bench.fc.snapshot()["scan"]["active"]
    bench.run_until(lambda: bench.fc.al_state is AlState.PREOP)
    assert bench.now - t0 == scan_us(3)


def cnf_record(bench: Bench, mark: int) -> list[tuple[float, str, str]]:
    return [(r["t"], r["machine"], r["to"]) for r in bench.records("state", mark)
            if r.get("machine") in ("cnf_button", "cnf")]


def test_tap_while_held_releases_after_the_whole_press() -> None:
    """The UI order "Hold CNF" ticked, then "Tap CNF (1 s)": the button was down 6 s, so its
    release runs the procedure (§2 "almeno tre secondi")."""
    bench = Bench()
    bench.settle()
    mark, t0 = bench.mark(), bench.now
    bench.apply("press_cnf")
    bench.run(5.0)
    assert bench.fc.snapshot()["cnf"]["held_s"] == 5.0
    bench.apply("hold_cnf", seconds=1.0)
    bench.run(3.0)
    release = (t0 + 6 * US) / US
    assert cnf_record(bench, mark)[:3] == [(t0 / US, "cnf_button", "pressed"),
                                           (release, "cnf_button", "released"),
                                           (release, "cnf", "resetting")]


def test_hold_ticked_during_a_timed_press_keeps_the_button_down() -> None:
    """"Hold CNF" after a timed press: down until it is unticked; ticking it twice is one
    press. The release then measures from the first press."""
    bench = Bench()
    bench.settle()
    mark, t0 = bench.mark(), bench.now
    bench.apply("hold_cnf", seconds=1.0)
    bench.run(0.5)
    bench.apply("press_cnf")
    bench.apply("press_cnf")
    bench.run(4.0)
    assert bench.fc.snapshot()["cnf"]["pressed"]
    bench.apply("release_cnf")
    assert cnf_record(bench, mark) == [(t0 / US, "cnf_button", "pressed"),
                                       (bench.now / US, "cnf_button", "released"),
                                       (bench.now / US, "cnf", "resetting")]


def test_release_during_a_timed_press_ends_it() -> None:
    """Unticking "Hold CNF" while a timed press runs lets go now; the scheduled release does
    not come again."""
    bench = Bench()
    bench.settle()
    mark, t0 = bench.mark(), bench.now
    bench.apply("hold_cnf", seconds=3.5)
    bench.run(1.0)
    bench.apply("release_cnf")
    bench.run(5.0)
    assert cnf_record(bench, mark) == [(t0 / US, "cnf_button", "pressed"),
                                       ((t0 + US) / US, "cnf_button", "released")]
