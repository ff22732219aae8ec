"""The Drive tab's Alarm row says what the alarm does in a trainee's words, as the Codes tab
does (devices/servo/alarms.py EFFECT_TEXT). It showed the model's note on the seed instead:
"motor overtemperature (none printed: stop on the emergency ramp, then torque off)", where
"none printed" (seed 004 ch. 3 prints no action for alarm 2) read as a second alarm state."""

from __future__ import annotations

import pytest

from app.ui.drive.drive_state import alarm_html
from devices.servo.alarms import EFFECT_TEXT, Effect


@pytest.mark.parametrize("effect", list(Effect))
def test_alarm_row_words_the_effect_for_a_trainee(effect: Effect) -> None:
    snap = {"alarm": {"code": 2, "name": "MOTOR_THERMAL",
                      "description": "motor overtemperature", "effect": effect.value}}
    html = alarm_html(snap)
    assert EFFECT_TEXT[effect] in html
    assert "none printed" not in html


def test_an_unknown_effect_is_shown_as_it_came() -> None:
    snap = {"alarm": {"code": 99, "name": "X", "description": "d", "effect": "coast"}}
    assert "— coast<" in alarm_html(snap)
