"""A caption that tells what a device does is on screen when it does it: not while the
picture still shows the state before (the player's Step stops at a caption step, so a
trainee reads the caption over that picture), nor after the picture has shown it for a
while under the caption before. Both were seen in review: trscat_outputs_fallback's "back to
OP" came 0.34 s after the TRS-CAT was in OP, under "falls to SAFEOP ... error outputs";
canopen_drive_alarm_reset's "the master resets the fault by SDO ... EMCY 0x0000" was shown
0.5 s before the SDO, over a drive in Fault."""

from __future__ import annotations

from tests.app.test_line_scenarios import pick

LEAD_S = 0.05  # a few cycles: what the eye cannot tell apart


def caption_at(name: str, words: str) -> float:
    found = [r["t"] for r in pick(name, "caption", "scenario") if words in r["text"]]
    assert len(found) == 1, (name, words, found)
    return found[0]


def test_trscat_back_to_op_caption_with_the_state_change() -> None:
    name = "trscat_outputs_fallback"
    shown = caption_at(name, "back to OP")
    back = pick(name, "slave_state", "master", position=1, to="OP")[-1]["t"]
    assert shown <= back <= shown + LEAD_S, (shown, back)


def test_canopen_fault_reset_caption_with_the_reset() -> None:
    name = "canopen_drive_alarm_reset"
    shown = caption_at(name, "0x6040 = 0x0080")
    reset = pick(name, "state", "drive_co", **{"from": "Fault"})[-1]["t"]
    emcy = pick(name, "emergency", "drive_co", code="0x0000")[-1]["t"]
    assert shown <= reset <= shown + LEAD_S and shown <= emcy <= shown + LEAD_S, \
        (shown, reset, emcy)
    # The caption before it says only what the picture shows then: the drive still in Fault
    cooled = caption_at(name, "has cooled")
    assert cooled < shown and "EMCY 0x0000" not in next(
        r["text"] for r in pick(name, "caption", "scenario") if r["t"] == cooled)


def test_fastcat_sm_watchdog_captions_with_the_fall_and_the_return() -> None:
    name = "fastcat_sm_watchdog"
    shown = caption_at(name, "sync error (0x001A)")
    trscat = pick(name, "al_status", "trscat", code="0x001A")[0]["t"]
    assert shown <= trscat <= shown + LEAD_S, (shown, trscat)
    shown = caption_at(name, "SM watchdog takes it to SAFEOP")
    fall = pick(name, "state", "fastcat", **{"from": "OP", "to": "SAFEOP"})[0]["t"]
    assert shown <= fall <= shown + LEAD_S, (shown, fall)
    assert pick(name, "al_status", "fastcat", t=fall, code="0x001B")
    shown = caption_at(name, "The frames flow again")
    back = pick(name, "state", "fastcat", **{"from": "SAFEOP", "to": "OP"})[-1]["t"]
    assert shown <= back <= shown + LEAD_S, (shown, back)


def test_fastcat_address_check_captions_with_the_alarm_its_reset_and_op() -> None:
    name = "fastcat_address_check"
    shown = caption_at(name, "compares its switch (3)")
    alarm = pick(name, "alarm", "fastcat", code="0x12", active=True)[0]["t"]
    assert shown <= alarm <= shown + LEAD_S, (shown, alarm)
    shown = caption_at(name, "alarm 0x12 clears")
    cleared = pick(name, "alarm", "fastcat", code="0x12", active=False)[0]["t"]
    assert shown <= cleared <= shown + LEAD_S, (shown, cleared)
    shown = caption_at(name, "in OP again")
    back = pick(name, "state", "fastcat", **{"from": "SAFEOP", "to": "OP"})[-1]["t"]
    assert shown <= back <= shown + LEAD_S, (shown, back)
