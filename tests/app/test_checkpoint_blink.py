"""A checkpoint whose caption says an LED blinks catches that LED lit.

A picture stands still at the checkpoint's simulated instant (docs/scenarios.md "Screenshots
for CI"), and the LED phase comes from that instant (docs/leds.md). A blink is lit while t
mod 0.4 s < 0.2 s, so a checkpoint at 5.0 s caught it dark: module_lost_in_op's "op" picture
showed seven dark yellow LEDs under "its modules' yellow LEDs blinking",
cnf_scan's "after_scan" the same under "the yellow LEDs blink", and trscat_expansion_mismatch's
"safeop_refused" a dark ERROR LED under "its ERROR LED blinking". A trainee reads a dark LED as
off, whatever the legend under the rail says.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario, run_scenario
from devices.leds import LedPattern, is_lit

SCENARIOS = Path(__file__).resolve().parents[2] / "static" / "scenarios"

# (scenario, checkpoint, device, the LEDs the caption names, the caption's words for the blink)
BLINKS = [
    ("module_lost_in_op", "op", "fastcat", r"\d+\.yellow", "yellow LEDs blinking"),
    ("cnf_scan", "after_scan", "fastcat", r"\d+\.yellow", "yellow LEDs blink"),
    ("trscat_expansion_mismatch", "safeop_refused", "trscat", r"ERROR", "ERROR LED blinking"),
    ("config_mismatch", "mismatch", "fastcat", r"ERR", "ERR blinks"),
    ("cpx_output_supply_low", "undervoltage", "cpx", r"PL", "PL blinks"),
]


def records(stem: str) -> list[dict]:
    scenario = load_scenario(SCENARIOS / f"{stem}.toml")
    rig = build_rig(load_rig_spec(scenario.rig or DEFAULT_RIG))
    return [e.to_record() for e in run_scenario(scenario, rig).events]


@pytest.mark.parametrize(("stem", "checkpoint", "device", "leds", "words"), BLINKS,
                         ids=[f"{b[0]}-{b[1]}" for b in BLINKS])
def test_the_blinking_led_the_caption_names_is_lit_in_the_picture(
        stem: str, checkpoint: str, device: str, leds: str, words: str) -> None:
    lines = records(stem)
    t = next(r["t"] for r in lines if r["event"] == "checkpoint" and r["name"] == checkpoint)
    caption = [r["text"] for r in lines if r["event"] == "caption" and r["t"] <= t][-1]
    assert words in " ".join(caption.split())
    patterns: dict[str, str] = {}
    for r in lines:
        if r["t"] <= t and r["event"] == "led" and r["device"] == device \
                and re.fullmatch(leds, r["led"]):
            patterns[r["led"]] = r["pattern"]
    assert patterns and set(patterns.values()) == {"blinking"}, patterns
    t_us = round(t * 1_000_000)
    dark = sorted(led for led, p in patterns.items() if not is_lit(LedPattern(p), t_us))
    assert not dark, f"{stem} {checkpoint} at {t} s: {dark} blinking but dark in the picture"


# (scenario, checkpoint, device, LED, the pattern the caption names, the caption's words):
# a flash is lit for 200 ms of its 1.2 s / 1.6 s period, so most instants catch it dark.
FLASHES = [
    ("fastcat_sm_watchdog", "watchdog", "fastcat", "ERR", "double_flash", "ERR double flash"),
    ("fastcat_sm_watchdog", "watchdog", "fastcat", "RUN", "single_flash", "RUN single flash"),
    ("fastcat_address_check", "address_alarm", "fastcat", "ERR", "single_flash",
     "ERR single flash"),
    ("fastcat_address_check", "address_alarm", "fastcat", "RUN", "blinking", "RUN blinking"),
]


@pytest.mark.parametrize(("stem", "checkpoint", "device", "led", "pattern", "words"), FLASHES,
                         ids=[f"{f[0]}-{f[1]}-{f[3]}" for f in FLASHES])
def test_the_flashing_led_the_caption_names_is_lit_in_the_picture(
        stem: str, checkpoint: str, device: str, led: str, pattern: str, words: str) -> None:
    lines = records(stem)
    t = next(r["t"] for r in lines if r["event"] == "checkpoint" and r["name"] == checkpoint)
    caption = [r["text"] for r in lines if r["event"] == "caption" and r["t"] <= t][-1]
    assert words in " ".join(caption.split())
    shown = [r["pattern"] for r in lines if r["t"] <= t and r["event"] == "led"
             and r["device"] == device and r["led"] == led][-1]
    assert shown == pattern
    assert is_lit(LedPattern(shown), round(t * 1_000_000)), f"{stem} {checkpoint} at {t} s: " \
        f"{led} {pattern} but dark in the picture"
