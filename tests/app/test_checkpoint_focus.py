"""Each example scenario's checkpoint picture is on the device its caption is about.

``scenario run --screenshots`` takes a checkpoint's picture where the last ``focus`` step left
the camera (and the left panel's tab, docs/dashboard.md "Focus"), under the last caption. A
sales walkthrough found captions about the TRS-CAT and the CPX-E-EC over pictures of the
master (trscat_expansion_mismatch ``safeop_refused``, cpx_short_circuit ``short_circuit``).

What a caption is about is a judgement, written down once in EXPECTED for every checkpoint
whose caption names a device; the tests check that the judgement names a device the caption
names, that no checkpoint is left unjudged, and that the scenario files focus as judged.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.scenario import Scenario, load_scenario

SCENARIOS = sorted((Path(__file__).resolve().parents[2] / "static" / "scenarios")
                   .glob("*.toml"))
# How captions name the default rig's devices (the line's bodies and the drive's axis).
NAMES = {
    "master": r"\bmaster\b",
    "fastcat": r"\bFastCAT\b|\bcoupler\b",
    "trscat": r"\bTRS-CAT\b",
    "cpx": r"\bCPX-E\b",
    "drive_ec": r"\bdrive_ec\b",
    "drive_co": r"\bdrive_co\b",
    "drive": r"\bdrive\b(?!_)|\bmotor\b",
}
# (scenario, checkpoint) -> the device the picture must be on; None: the whole line (no focus
# step before it), where every device of the line is in view and the left panel stays on the
# FastCAT's State tab.
EXPECTED: dict[tuple[str, str], str | None] = {
    # "Encoder 1 of the AX2 (FastCAT module 7) is homed: 0x6660 bit 12 ...": the module
    # (focus "fastcat:7"), its red LED dark; it showed the zero-cycle command's caption.
    ("ax2_homing", "homed"): "fastcat",
    # "The line powers up: the master sees link, then brings ... to OP": the Line tab's
    # slave table shows every slave's state.
    ("cable_pulled", "line_in_op"): "master",
    ("cable_pulled", "cable_pulled"): "cpx",  # cut off behind cable 2
    ("cable_pulled", "recovered"): "master",  # "the master finds both slaves again"
    # "drive_co's motor overheats ...": its Drive tab (CiA 402 Fault, alarm 2); off the line,
    # its axis is in the whole line's view (docs/scenarios.md, focus on a drive).
    ("canopen_drive_alarm_reset", "overtemperature"): "drive_co",
    ("canopen_drive_alarm_reset", "reset"): "drive_co",
    ("cnf_scan", "op"): None,  # the coupler's own scan: the whole rail in view
    ("cpx_output_supply_low", "supplied"): "cpx",
    ("cpx_output_supply_low", "undervoltage"): "cpx",  # PL blinking, SF, the Slave tab
    ("config_mismatch", "mismatch"): None,
    ("cpx_short_circuit", "output_on"): "cpx",
    ("cpx_short_circuit", "short_circuit"): "cpx",  # the module's red LED, SF, 0x10F3
    ("dc_sync_lost", "compensating"): "master",  # the master's DC state
    # "... the master cannot follow the network clock any more: NOT_SYNCHRONIZED": the
    # master's screen, and the Line tab's slave table with the DC slaves in SAFEOP.
    ("dc_sync_lost", "not_synchronized"): "master",
    ("dc_sync_lost", "resynchronized"): "master",
    ("drive_jammed_load", "following_error"): "drive",  # alarm 16 on the Drive tab
    # "... the alarm reset clears alarm 16 ... the drive is enabled again": its Drive tab.
    ("drive_jammed_load", "recovered"): "drive",
    # The FastCAT's own behaviours (seed 000 §6.19, §7.7): its LEDs and its State tab.
    ("fastcat_address_check", "check_enabled"): "fastcat",
    ("fastcat_address_check", "address_alarm"): "fastcat",
    ("fastcat_address_check", "recovered"): "fastcat",
    ("fastcat_sm_watchdog", "outputs_on"): "fastcat",
    # "... the FastCAT's SM watchdog ... The CPX-E-EC and the drive fall with 0x001B too": the
    # coupler is the lesson, the others a side note.
    ("fastcat_sm_watchdog", "watchdog"): "fastcat",
    ("fastcat_sm_watchdog", "recovered"): "fastcat",
    ("module_lost_in_op", "op"): None,  # the whole line in OP, the FastCAT's State tab
    ("module_lost_in_op", "recovered"): None,
    ("too_many_analog", "max_analog_alarm"): None,  # one coupler, no tabs: the whole rail
    ("trscat_expansion_mismatch", "line_in_op"): None,
    ("trscat_expansion_mismatch", "safeop_refused"): "trscat",  # PREOP, ERROR blinking
    ("trscat_expansion_mismatch", "fixed"): "trscat",
    ("trscat_outputs_fallback", "outputs_on"): "trscat",
    ("trscat_outputs_fallback", "outputs_fallback"): "trscat",
    # "... takes the TRS-CAT back to OP and the outputs follow the PLC again": its LEDs.
    ("trscat_outputs_fallback", "recovered"): "trscat",
}


def checkpoints(scenario: Scenario) -> list[tuple[str, str, str | None]]:
    """(checkpoint, caption shown, focused device) at each checkpoint, in play order."""
    caption, focus, out = "", None, []
    for step in scenario.steps:
        if step.kind == "caption":
            caption = step.text
        elif step.kind == "focus":
            focus = step.target.split(":", 1)[0]
        elif step.kind == "checkpoint":
            out.append((step.text, caption, focus))
    return out


def named(caption: str) -> set[str]:
    return {device for device, pattern in NAMES.items() if re.search(pattern, caption)}


ALL = [(path.stem, name, caption, focus) for path in SCENARIOS
       for name, caption, focus in checkpoints(load_scenario(path))]


def test_every_checkpoint_naming_a_device_is_judged() -> None:
    unjudged = [(stem, name) for stem, name, caption, _ in ALL
                if named(caption) and (stem, name) not in EXPECTED]
    assert unjudged == []
    assert set(EXPECTED) <= {(stem, name) for stem, name, _, _ in ALL}  # no stale entry


# The checkpoints whose caption names a device (every one is judged: the test above)
JUDGED = [c for c in ALL if (c[0], c[1]) in EXPECTED]


@pytest.mark.parametrize(("stem", "name", "caption", "focus"), JUDGED,
                         ids=[f"{a}-{b}" for a, b, _, _ in JUDGED])
def test_the_checkpoint_is_focused_on_the_device_of_its_caption(
        stem: str, name: str, caption: str, focus: str | None) -> None:
    expected = EXPECTED[(stem, name)]
    assert expected is None or expected in named(caption), (expected, caption)
    assert focus == expected, (f"{stem} checkpoint {name}: focus {focus!r}, the caption is "
                               f"about {expected!r}: {caption}")


@pytest.mark.parametrize(("stem", "name", "caption"), [c[:3] for c in ALL],
                         ids=[f"{a}-{b}" for a, b, _, _ in ALL])
def test_every_checkpoint_picture_has_a_caption(stem: str, name: str, caption: str) -> None:
    """The examples are the sales demos: each picture says in words what it shows (README "For
    sales and support demos"). too_many_analog had no caption: its picture was the rail and a
    red alarm, with nothing on screen a non-specialist could follow."""
    assert caption.strip(), f"{stem} checkpoint {name}: no caption before it"
