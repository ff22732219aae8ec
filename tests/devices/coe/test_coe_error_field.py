"""0x1003:1 of the drive holds the 0x603F code in bits 0-15 and the alarm number in bits 16-31
(docs/canopen.md; seed 004 ch. 4 "Emergency Message" leaves the rest of the entry to the
device, DS 301 "additional information"). 0x00108611 is alarm 16, not "10": the Objects tab
says so, named from the drive's alarm table (devices/servo/alarms.py)."""

from __future__ import annotations

import pytest
from coe_bench import make_bench

from app.ui.panels.object_dictionary import read_rows, render
from devices.ethercat import AlState
from devices.servo import alarms

SAID = "0x00108611 = alarm 16 FOLLOWING_ERROR, code 0x8611"


def test_objects_tab_names_the_alarm_in_0x1003_sub1() -> None:
    bench = make_bench()
    bench.go(AlState.PREOP)
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(1)
    assert bench.read(0x1003, 1) == 0x0010_8611  # the bytes stay as they were
    assert f"<td>{SAID}</td>" in render(read_rows(bench.slave), "1003:1")


def test_an_empty_history_says_so() -> None:
    bench = make_bench()
    assert "<td>0x00000000 = empty</td>" in render(read_rows(bench.slave), "1003:1")


@pytest.mark.parametrize(("word", "said"), [
    (0x0010_8611, SAID),
    (0x0023_5530, "0x00235530 = alarm 35 ECAT_EEPROM, code 0x5530"),
    (0x0016_1000, "0x00161000 = alarm 22 ABS_ENCODER_HOMING, code 0x1000"),
    (0x0000_8130, "0x00008130 = code 0x8130, no drive alarm (the node's own emergency)"),
    (0x0063_8611, "0x00638611 = alarm 99 (not in the drive's table), code 0x8611"),
    (0, "0x00000000 = empty"),
])
def test_error_field_text(word: int, said: str) -> None:
    assert alarms.error_field_text(word, alarms.alarm_table("ethercat")) == said
