"""The drive's "cause removed" log line names the reset of the drive's own fieldbus.

Before, every drive read "(reset with control word bit 3)": bit 3 is Alm_rst of the Modbus R00
register (seed 004 ch. 1 / ch. 2); a CANopen or EtherCAT (CoE) master resets by writing 0x80
to 0x6040, bit 7 (ch. 4 examples "0x0080"; ch. 5 "Reset allarmi": "scrittura 0x80 su oggetto
0x6040"). Profinet: docs/servo-drive.md ("Reset").
"""

from __future__ import annotations

import pytest
from servo_helpers import make_sim

from devices.servo.drive import DriveConfig


@pytest.mark.parametrize(("fieldbus", "hint"), [
    ("modbus", "R00 bit 3"),
    ("canopen", "0x6040 = 0x80 (bit 7)"),
    ("ethercat", "0x6040 = 0x80 (bit 7)"),
    ("profinet", "Control Word = 0x80 (bit 7)"),
])
def test_clear_alarm_names_the_reset_of_the_fieldbus(fieldbus: str, hint: str) -> None:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    sim.drive.apply("inject_alarm", {"code": 16})
    sim.run(5)
    sim.drive.apply("clear_alarm", {"code": 16})
    sim.run(1)
    texts = [e["text"] for e in sim.kinds("log") if "removed" in e.get("text", "")]
    assert texts == [f"cause of alarm 16 removed (reset with {hint})"], texts
