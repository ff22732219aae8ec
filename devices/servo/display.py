"""The drive's two-digit 7-segment display.

Seed 004 ch. 5 "Salvataggio in flash dei parametri": "Fr" with the axis disabled, two dashes
while saving, "Fr" again when the save is done; ch. 5 "Codici allarmi specifici": alarms show on
the display. What it shows in torque is not printed; the model shows "En" (docs/servo-drive.md
§Display).
"""

from __future__ import annotations

FREE = "Fr"
SAVING = "--"
ENABLED = "En"
OFF = ""


def display_text(powered: bool, saving: bool, alarm_code: int, in_torque: bool) -> str:
    if not powered:
        return OFF
    if saving:
        return SAVING
    if alarm_code:
        return f"{alarm_code:2d}"
    return ENABLED if in_torque else FREE
