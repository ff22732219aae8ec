"""The Drive tab says what to press after an alarm reset that left the axis released.

Since session 23 an alarm reset with R00's Ten_cmd held leaves the drive in Switch on disabled
until Ten_cmd goes 0 -> 1 (docs/servo-drive.md "Re-enabling after an alarm"; seed 004 ch. 2 /
ch. 6 reset with the enable off). The panel's *Alarm reset* keeps R00, so after it the tab read
"Switch on disabled" next to "R00 control 0x0003: Ten_cmd, Ien_cmd", and Home, Move and Start
did nothing with no word: only Jog's notice named the fresh enable. The CiA 402 row now says it.
"""

from __future__ import annotations

import random

from app.ui.drive.drive_state import state_rows
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

FOLLOWING_ERROR = 16


class Bench:
    def __init__(self) -> None:
        self.drive = ServoDrive("drive", random.Random(1), DriveConfig(), MemoryFlash())
        self.t_us = 0
        self.run(100)  # past the self test

    def run(self, ms: int) -> None:
        self.t_us += ms * 1_000
        self.drive.step(self.t_us)

    def apply(self, action: str, **args: object) -> object:
        return self.drive.apply(action, dict(args))

    def state_row(self) -> str:
        return dict(state_rows(self.drive.snapshot()))["CiA 402 state"]


def _reset_with_ten_cmd_held() -> Bench:
    bench = Bench()
    bench.apply("enable", on=True)
    bench.run(50)
    bench.apply("inject_alarm", code=FOLLOWING_ERROR)
    bench.apply("clear_alarm", code=FOLLOWING_ERROR)
    bench.run(500)
    assert bench.apply("alarm_reset") is None  # the panel's pulse, R00 = 3 kept
    bench.run(50)
    return bench


def test_after_the_panel_s_reset_the_state_row_says_press_enable() -> None:
    bench = _reset_with_ten_cmd_held()
    row = bench.state_row()
    assert "Switch on disabled" in row
    assert "press Enable" in row
    assert bench.drive.snapshot()["released_by_reset"]


def test_the_note_goes_with_the_fresh_enable() -> None:
    bench = _reset_with_ten_cmd_held()
    bench.apply("enable", on=True)
    bench.run(50)
    row = bench.state_row()
    assert "Operation enabled" in row
    assert "press Enable" not in row
    assert not bench.drive.snapshot()["released_by_reset"]


def test_no_note_on_a_fresh_drive_or_after_the_seed_s_reset() -> None:
    bench = Bench()
    assert "press Enable" not in bench.state_row()  # Switch on disabled, R00 = 0
    bench.apply("enable", on=True)
    bench.run(50)
    bench.apply("inject_alarm", code=FOLLOWING_ERROR)
    bench.apply("clear_alarm", code=FOLLOWING_ERROR)
    bench.run(500)
    bench.apply("write_register", register=0, value=0x08)  # ch. 2 / ch. 6: 8, Ten_cmd low
    bench.run(50)
    assert "Switch on disabled" in bench.state_row()
    assert "press Enable" not in bench.state_row()
