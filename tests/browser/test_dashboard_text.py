"""What the dashboard writes, without a browser: texts, tables, LED colours from sim time.

The views are pure functions of snapshots and events, so they are tested here directly; the
browser tests (test_dashboard.py) check that the page shows them.
"""

from __future__ import annotations

import pytest
from helpers import LiveDashboard

from app.ui.dashboard import fault_options
from app.ui.panels.control import FaultOption, fault_targets, module_options
from app.ui.panels.event_log import LogRow, event_message, render_rows
from app.ui.panels.object_dictionary import (
    OdRow,
    format_value,
    matches,
    parse_address,
    parse_value,
    render,
)
from app.ui.panels.state import al_code_text, state_rows
from app.ui.rail_scene import LED_OFF, LIT, led_color, module_led_legend, slot_ranges
from devices.device import CommandError
from devices.ethercat import al_status_name
from devices.events import AlarmChanged, Caption, EmergencySent, LedChanged, StateChanged
from devices.fastcat.alarms import CODE_TABLES, COUPLER_CODES, MODULE_CODES
from devices.leds import PATTERN_TIMING_MS, LedPattern


# ---- faults (seed 000 §7.5, §7.6) ---------------------------------------------------------
def test_fault_dropdown_lists_every_code_of_both_tables() -> None:
    options = fault_options()
    assert len(options) == len(COUPLER_CODES) + len(MODULE_CODES)
    assert {(o.table, o.code) for o in options} == \
        {(t, c) for t, rows in CODE_TABLES.items() for c in rows}


def test_fault_option_text_and_reference() -> None:
    option = FaultOption("coupler", 0x04, "MISSING_NODE_ANSWER", "No answer from the node")
    # The label is what the box can show; the description is the box's hint.
    assert option.label == "0x04 MISSING_NODE_ANSWER"
    assert option.detail == "0x04 MISSING_NODE_ANSWER: No answer from the node (seed 000 §7.5)"
    assert option.ref == "coupler:0x04"  # unambiguous: 0x04 is ALARM_IO_FAULT in §7.6


def test_fault_targets_use_the_module_numbers_of_the_bus() -> None:
    """An empty slot shifts the bus numbering: byte 0 of the emergency is the module number."""
    rail = [{"slot": 1, "type": "DB16", "module_number": 1}, {"slot": 2, "type": None},
            {"slot": 3, "type": "AX2", "module_number": 2}]
    assert fault_targets(rail) == ["1 DB16", "2 AX2"]
    assert module_options(rail) == ["1 DB16", "2 (empty)", "3 AX2"]


# ---- state panel (§6.16, §6.23, §7.7) -------------------------------------------------------
@pytest.mark.parametrize(("code", "text"), [
    (0x0000, "No error"),
    (0x0052, "External hardware not ready"),
    (0x8204, "module 2: coupler code 0x04 MISSING_NODE_ANSWER"),  # the §7.7 example
    (0x8012, "coupler: coupler code 0x12 ADDRESS_MASTER_NOT_OK"),
    (0x8315, "module 3: coupler code 0x15 MAX_ANALOG_MODULES"),
    (0x8400, "Manufacturer specific"),  # no coupler code: not a FastCAT code (§7.7)
])
def test_al_status_code_text(code: int, text: str) -> None:
    assert text in al_code_text(code)


@pytest.mark.parametrize(("value", "text"), [
    (0x01, "INIT"), (0x02, "PREOP"), (0x12, "PREOP + error"), (0x08, "OP"),
    (0x14, "SAFEOP + error"),
])
def test_al_status_register_text(value: int, text: str) -> None:
    assert al_status_name(value) == text


def test_state_rows_show_fault_emergency_word_and_alarm() -> None:
    snap = {"powered": True, "esm": "PREOP", "requested": "SAFEOP", "fault_active": True,
            "emergency_data": 0x04000002, "al_status": 0x12, "al_status_code": 0x8204,
            "alarm": {"table": "coupler", "code": 4, "name": "MISSING_NODE_ANSWER",
                      "description": "No answer from the node", "module": 2,
                      "resettable": True, "cause_present": False},
            "cnf": {"pressed": False, "held_s": 0.0, "phase": "idle"},
            "scan": {"active": False, "done": 7, "total": 7},
            "stored_config": ["DB16"], "detected": ["DB16"], "rotary_switch": 3,
            "rotary_read": 1, "address_check": True,
            "injected": [{"fault": "MISSING_NODE_ANSWER", "code": 4, "module": 2},
                         {"fault": "ADDRESS_ERROR", "code": 0x20, "module": None}]}
    rows = dict(state_rows(snap))
    assert rows["Injected"] == "0x04 MISSING_NODE_ANSWER on module 2, 0x20 ADDRESS_ERROR"
    assert "none" in dict(state_rows({**snap, "injected": []}))["Injected"]
    assert "TRUE" in rows["Fault active"]
    assert rows["0x5400"] == "0x04000002"
    assert rows["AL status"] == "0x0012 PREOP + error"
    assert "requested SAFEOP" in rows["ESM state"]
    assert "MISSING_NODE_ANSWER" in rows["Alarm"] and "cause gone" in rows["Alarm"]
    assert "0x5302 = 1" in rows["Rotary switch"] and "check on" in rows["Rotary switch"]


# ---- event log ------------------------------------------------------------------------------
def test_event_messages_of_device_events() -> None:
    assert event_message(EmergencySent(1, "fastcat", 0xFF00, 0x81, bytes([2, 0, 0, 4, 0]))) \
        == ("Emergency sent (code 0xFF00, register 0x81, data 02 00 00 04 00)", True)
    assert event_message(StateChanged(1, "fastcat", "OP", "PREOP")) == \
        ("ESM state change 'OP' -> 'PREOP'", False)
    assert event_message(AlarmChanged(1, "fastcat", "0x04", "MISSING_NODE_ANSWER", False, 2)) \
        == ("alarm 0x04 MISSING_NODE_ANSWER module 2 cleared", False)
    assert event_message(LedChanged(1, "fastcat", "ERR", "blinking")) is None


def test_log_rows_are_escaped() -> None:
    html = render_rows([LogRow(0, 0, "(65535)", "12/11/2019 14.51.30 421 ms",
                               "<script>x</script>", False)])
    assert "<script>" not in html and "&lt;script&gt;" in html
    assert "12/11/2019<br>14.51.30 421 ms" in html


# ---- object dictionary ------------------------------------------------------------------
def test_object_filter_finds_per_module_families() -> None:
    """§6: "0x2104-0x21F4" = 0x2104 + 0x10 * (N - 1); typing the base finds every module's."""
    rows = [OdRow(0x2104 + 0x10 * n, 0, "Analog input filter", "UINT", "rw", 4000)
            for n in range(3)] + [OdRow(0x5400, 0, "Emergency data", "UDINT", "ro", 0)]
    assert [r.index for r in rows if matches(r, "0x2104")] == [0x2104, 0x2114, 0x2124]
    assert [r.index for r in rows if matches(r, "2114")] == [0x2114]
    assert [r.index for r in rows if matches(r, "emergency")] == [0x5400]
    assert "no object matches" in render(rows, "nothing-like-this")
    assert "generates it at the end of the internal-bus scan" in render([], "")


@pytest.mark.parametrize(("text", "address"), [
    ("0x5200:1", (0x5200, 1)), ("5400", (0x5400, 0)), ("0x1018:4", (0x1018, 4)),
])
def test_parse_address(text: str, address: tuple[int, int]) -> None:
    assert parse_address(text) == address


def test_parse_address_refuses_garbage_and_values_parse() -> None:
    with pytest.raises(CommandError):
        parse_address("zz:1")
    assert parse_value("0x10") == 16 and parse_value("true") == 1 and parse_value("ab") == "ab"
    assert format_value(0x04000002, "UDINT") == "67108866 (0x04000002)"
    assert format_value(True, "BOOL") == "1"


# ---- LEDs (ETG.1300 timings, devices/leds.py) --------------------------------------------
@pytest.mark.parametrize("pattern", list(PATTERN_TIMING_MS))
def test_led_colour_follows_the_pattern_timing(pattern: LedPattern) -> None:
    """The colour is lit during the pattern's on-spans and dark in its off-spans, at the
    simulated time: the same instant gives the same picture."""
    t_ms = 0
    for i, span in enumerate(PATTERN_TIMING_MS[pattern]):
        middle_us = (t_ms + span // 2) * 1000
        expected = LIT["red"] if i % 2 == 0 else LED_OFF
        assert led_color("red", pattern.value, middle_us) == expected
        t_ms += span


def test_led_legend_names_patterns_and_slots() -> None:
    leds = {"RUN": "on", "1.red": "on", "2.red": "on", "3.red": "off", "4.red": "on",
            "1.yellow": "blinking", "2.yellow": "blinking"}
    legend = module_led_legend(leds)
    assert "red on: 1-2, 4" in legend and "yellow blinking: 1-2" in legend
    assert slot_ranges([7, 1, 2, 3, 5]) == "1-3, 5, 7"


# ---- the live view, without a browser ----------------------------------------------------
def test_scene_leds_follow_simulated_time(live: LiveDashboard) -> None:
    """In alarm the coupler's ERR LED blinks (ETG.1300: 200 ms on, 200 ms off); the scene
    shows it lit or dark by the simulated clock, and every module's red LED steady (§7)."""
    live.advance(4.0)
    live.command("fastcat/2", "inject_fault", {"fault": "MISSING_NODE_ANSWER"})
    live.advance(0.3)
    assert live.snapshot()["leds"]["ERR"] == "blinking"
    seen = set()
    for _ in range(4):
        live.advance(0.2)
        t_us = live.runtime.frame.t_us
        lit = is_lit_blinking(t_us)
        assert live.dashboard.scene_colors()["ERR"] == (LIT["red"] if lit else LED_OFF)
        seen.add(lit)
        assert live.dashboard.scene_colors()["5.red"] == LIT["red"]
    assert seen == {True, False}


def test_scenario_caption_shows_above_the_rail(live: LiveDashboard) -> None:
    assert live.dashboard.caption == ""
    # A scenario played into the runtime journals its captions like device events.
    live.runtime.journal([Caption(live.runtime.frame.t_us, "scenario",
                                  text="Module 2 stops answering")])
    live.advance(0.1)
    assert live.dashboard.caption == "Module 2 stops answering"


def is_lit_blinking(t_us: int) -> bool:
    return (t_us // 1000) % 400 < 200
