"""The CANopen tab's "Last SDO" row reads as a sentence: service, direction, object, result.

The UI audit saw "node 2 ->: download 0x6040:00 done" (the node's answer as the bus monitor
decodes it, arrow and colon run together, the value written gone). The row now joins the
master's request and the node's answer (DS 301 expedited and segmented SDO, seed 004 ch. 4):
"Download (write) 0x1017:00 = F4 01 to node 2: done."
"""

from __future__ import annotations

import re
from typing import Any

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.drive.canopen_panel import status_rows
from devices.canopen import master_frames as mf

NODE = "drive_co-can"  # the default rig's drive on CANopen


@pytest.fixture
def rig() -> Any:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(1000):  # the node's boot-up
        rig.step()
    return rig


def last_sdo(rig: Any, frame: mf.Frame) -> str:
    node = rig.devices[NODE]
    node.receive(frame.can_id, frame.data)
    for _ in range(20):  # the answer leaves within a few ms at 500 kbit/s
        rig.step()
    snap = node.snapshot()
    drive = rig.devices[snap["drive"]].snapshot()
    row = dict(status_rows(snap, drive))["Last SDO"]
    return re.sub("<[^>]+>", "", row).replace("&gt;", ">").replace("&lt;", "<")


def test_download_reads_as_a_sentence(rig: Any) -> None:
    node_id = int(rig.devices[NODE].node_id)
    text = last_sdo(rig, mf.sdo_download(node_id, 0x1017, 0, 500, 2))
    assert text == f"Download (write) 0x1017:00 = F4 01 to node {node_id}: done.", text
    assert "->:" not in text


def test_upload_names_the_value_read(rig: Any) -> None:
    node_id = int(rig.devices[NODE].node_id)
    text = last_sdo(rig, mf.sdo_upload(node_id, 0x1017, 0))
    assert text == f"Upload (read) 0x1017:00 from node {node_id}: value 00 00.", text


def test_an_abort_says_why(rig: Any) -> None:
    node_id = int(rig.devices[NODE].node_id)
    text = last_sdo(rig, mf.sdo_download(node_id, 0x1000, 0, 1, 4))  # device type: read only
    assert text.startswith(f"Download (write) 0x1000:00 = 01 00 00 00 to node {node_id}: "
                           "aborted by the node, 0x06010002"), text
