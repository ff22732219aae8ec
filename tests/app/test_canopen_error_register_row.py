"""The CANopen tab's Error register row names the set bits of 0x1001 in seed 004 ch. 4's words
("Bit / Error cause": Generic Error, Current, ..., Device Profile Specific), after the hex.

It showed "0x21" alone, while the Objects tab, the Codes tab and the Slave tab already read a
0x1001 value in words (``devices.canopen.emcy.REGISTER_WORDS``, the one table of those bits).
"""

from __future__ import annotations

import html
import re
from typing import Any

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.drive.canopen_panel import status_rows

NODE = "drive_co-can"  # the default rig's drive on CANopen


@pytest.fixture
def rig() -> Any:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(1000):  # the node's boot-up
        rig.step()
    return rig


def error_row(rig: Any) -> str:
    snap = rig.devices[NODE].snapshot()
    drive = rig.devices[snap["drive"]].snapshot()
    return html.unescape(re.sub("<[^>]+>", "", dict(status_rows(snap, drive))["Error register"]))


def test_a_clear_register_says_no_error(rig: Any) -> None:
    assert error_row(rig).startswith("0x00 (no error) · 0x1003: empty"), error_row(rig)


def test_a_following_error_names_its_bits(rig: Any) -> None:
    drive = rig.devices[rig.devices[NODE].snapshot()["drive"]]
    drive.apply("inject_alarm", {"code": "16"})  # 0x8611: DSP 402 positioning, bit 5
    for _ in range(50):
        rig.step()
    row = error_row(rig)
    assert row.startswith("0x21 (Generic Error, Device Profile Specific) · 0x1003: "), row


def test_the_row_reads_the_one_table() -> None:
    node = {"active": True, "error_register": 0xBE}  # the named bits but generic and reserved
    row = html.unescape(dict(status_rows(node, {}))["Error register"])
    assert row.startswith("0xBE (Current, Voltage, Temperature, Communication Error, "
                          "Device Profile Specific, Manufacturer Specific)"), row
