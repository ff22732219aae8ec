"""The Drive tab names the injected alarm causes for the instructor, and a refused alarm reset
says why (trainee-eyes review, session 14: Alarm reset with an injected alarm changed nothing on
screen, and only the drive log below the plots said "alarm 16 persists").

The *Injected* row is a :data:`app.ui.style.CAUSE_ROWS` row, as the FastCAT's and the slaves':
hidden on a trainee's page (docs/classroom.md); the refusal's text for a trainee is the model's
answer alone, "the cause persists", never the injected cause.
"""

from __future__ import annotations

from app.ui.drive.axis_scene import legend_parts, legend_text
from app.ui.drive.drive_commands import reset_refusal_text
from app.ui.drive.drive_state import DriveLog, state_rows
from app.ui.style import INSTRUCTOR_CLASS, kv_table
from devices.events import AlarmChanged, LogLine
from devices.servo.actions import CAUSE_REMOVED_LOG

IN_FAULT = {"powered": True, "ds402_state": "Fault", "alarm": {"code": 16,
            "name": "FOLLOWING_ERROR", "description": "", "effect": ""}, "alarms": [16]}
INJECTED = [{"code": 16, "name": "FOLLOWING_ERROR"}]
WHY = "alarm 16 persists: the cause persists"


def test_the_injected_row_names_the_causes_for_the_instructor_only() -> None:
    rows = dict(state_rows({**IN_FAULT, "injected": INJECTED}))
    assert "16 FOLLOWING_ERROR" in rows["Injected"]
    assert "none" in dict(state_rows({**IN_FAULT, "injected": []}))["Injected"]
    html = kv_table(state_rows({**IN_FAULT, "injected": INJECTED}), "fr-drive")
    assert f'<tr class="{INSTRUCTOR_CLASS}"><th>Injected</th><td>16 FOLLOWING_ERROR' in html


def test_a_trainee_reads_the_models_reason_and_no_injected_cause() -> None:
    text = reset_refusal_text(WHY, [])
    assert text == WHY
    assert "inject" not in text.lower()


def test_the_instructor_reads_which_injected_cause_holds_the_alarm() -> None:
    text = reset_refusal_text(WHY, INJECTED)
    assert text.startswith(WHY)
    assert "injected: 16 FOLLOWING_ERROR" in text and "Clear alarm" in text


def test_a_jammed_load_is_the_instructors_causes_row_not_the_consents() -> None:
    """The jam (an injected physical cause) was a badge in the shared TEN / IEN row."""
    rows = dict(state_rows({**IN_FAULT, "ten": True, "ien": True, "jammed": True}))
    assert "load jammed" in rows["Causes"]
    assert "jammed" not in rows["TEN / IEN"]
    assert "Causes" not in dict(state_rows(IN_FAULT))  # only while jammed, as the badge was
    html = kv_table(state_rows({**IN_FAULT, "jammed": True}), "fr-drive")
    assert f'<tr class="{INSTRUCTOR_CLASS}"><th>Causes</th>' in html


def test_with_trainees_the_scene_and_the_drive_log_name_no_jam() -> None:
    snap = {"position_counts": 0, "velocity": 0.0, "limits": {"home": True}, "jammed": True}
    assert "load jammed" in legend_text(snap)  # an open rig: as before
    assert "jammed" not in " · ".join(legend_parts(snap, causes=False))
    events = [LogLine(1, "drive", text="load jammed"), LogLine(2, "drive", text="power off")]
    for causes, shown in ((True, True), (False, False)):
        log = DriveLog(causes=causes)
        log.add(events)
        assert ("load jammed" in log.html("drive")) is shown
        assert "power off" in log.html("drive")


def test_with_trainees_the_drive_log_does_not_tell_a_cause_was_removed() -> None:
    """clear_alarm's "cause of alarm 16 removed" (the instructor's, or the repair of a right
    answer) told the trainees which alarm had been injected; the drive logs no such line,
    its alarm stays latched until a reset (tests/devices/servo/test_servo_reset_hint.py pins
    the model's text)."""
    removed = CAUSE_REMOVED_LOG.format(number=16, hint="R00 bit 3")
    events = [AlarmChanged(1, "drive", code=16, name="FOLLOWING_ERROR", active=True),
              LogLine(2, "drive", text=removed)]
    for causes, shown in ((True, True), (False, False)):
        log = DriveLog(causes=causes)
        log.add(events)
        assert ("cause of alarm 16 removed" in log.html("drive")) is shown
        assert "alarm 16 FOLLOWING_ERROR raised" in log.html("drive")
