"""The Drive tab's Outputs row shows every CN2 output of seed 004 ch. 2 "I/O digitali": pin 12
End of Job, pin 13 (a plain digital out, R50 / 0x60FE:1 bit 1 with R49 bit 1), pin 15 Near to
target, pin 16 Brake. Pin 13 was missing: a trainee who set R49 = R50 = 2 saw nothing change.
"""

from __future__ import annotations

import random

from app.ui.drive.drive_state import state_rows
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive


def _outputs_row(writes: dict[int, int]) -> str:
    drive = ServoDrive("drive", random.Random(1), DriveConfig(), MemoryFlash())
    drive.step(60_000)  # past the self test
    for n, value in writes.items():
        drive.write_register(n, value)
    drive.step(61_000)
    return dict(state_rows(drive.snapshot()))["Outputs"]


def test_pin_13_is_shown_off_by_default() -> None:
    assert "pin 13 off" in _outputs_row({})


def test_pin_13_follows_r50_bit_1_where_r49_makes_it_an_output() -> None:
    assert "pin 13 on" in _outputs_row({49: 0x2, 50: 0x2})
    assert "pin 13 off" in _outputs_row({49: 0x0, 50: 0x2})  # not configured as an output
