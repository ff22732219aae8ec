"""The Drive tab's log keeps each drive's own last events (docs/dashboard.md §Drive log).

The log serves every drive of the rig while the tab shows one: a busy drive (the Modbus one
jogging, homing) must not push a quiet drive's events out of its rows. drive_ec in Fault with
alarm 34 read "no drive events yet" after the Modbus drive's events filled a shared list
(trainee-eyes review, session 14, screenshot 32_drive_ec.png).
"""

from __future__ import annotations

from app.ui.drive.drive_state import LOG_ROWS, DriveLog
from devices.events import AlarmChanged, LogLine


def test_a_busy_drive_does_not_push_out_another_drives_events() -> None:
    log = DriveLog()
    log.add([AlarmChanged(1_000, "drive_ec", "34", "SYNC_TIMEOUT", True)])
    log.add(LogLine(2_000 + i, "drive", text=f"mode change {i}") for i in range(3 * LOG_ROWS))
    quiet = log.html("drive_ec")
    assert "alarm 34 SYNC_TIMEOUT raised" in quiet and "no drive events yet" not in quiet
    busy = log.html("drive")
    assert busy.count("<li") == LOG_ROWS  # still bounded: the drive's last 12
    assert f"mode change {3 * LOG_ROWS - 1}" in busy and "mode change 0<" not in busy


def test_clear_forgets_every_drive() -> None:
    log = DriveLog()
    log.add([LogLine(1_000, "drive", text="homing"), LogLine(1_000, "drive_co", text="save")])
    log.clear()
    assert "no drive events yet" in log.html("drive")
    assert "no drive events yet" in log.html("drive_co")
