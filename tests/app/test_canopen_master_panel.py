"""The CANopen master's Heartbeat (ms) box shows the node's 0x1017 and follows it.

The UI audit: the box read 1000 (the widget's initial value) while the drive's producer
heartbeat time 0x1017 was 0, so "Set heartbeat" seemed to have been done already. The box is
a form field pre-filled from the model (a ClientMirror, docs/dashboard.md): it takes 0x1017
when it changes, by this master's SDO or any other, and keeps what a user types until then.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from served_dashboard import drawn, served_default_rig

from app.screenshots import ServedRig
from app.ui.drive import canopen_master as cm
from app.ui.drive.canopen_panel import CanOpenMaster
from devices.canopen import master_frames as mf

DRIVE, NODE = "drive_co", "drive_co-can"  # the default rig's drive on CANopen


@pytest.fixture
def served() -> Iterator[ServedRig]:
    with served_default_rig(1.0) as live:  # the node's boot-up
        yield live


def master_of(live: ServedRig) -> CanOpenMaster:
    drives = live.dashboard.drives
    assert drives is not None and drives.master is not None
    drives.select(DRIVE)
    return drives.master


def test_heartbeat_box_shows_0x1017(served: ServedRig) -> None:
    master = master_of(served)
    drawn(served)
    node = served.runtime.rig.devices[NODE]
    assert node.snapshot()["heartbeat_ms"] == 0
    assert int(master.heartbeat_box.value) == 0


def test_heartbeat_box_follows_an_sdo_download(served: ServedRig) -> None:
    master = master_of(served)
    drawn(served)
    node = served.runtime.rig.devices[NODE]
    frame = mf.sdo_download(int(node.node_id), *cm.HEARTBEAT, 250, 2)
    served.runtime.submit(lambda: node.receive(frame.can_id, frame.data)).result(10)
    drawn(served)
    assert node.snapshot()["heartbeat_ms"] == 250
    assert int(master.heartbeat_box.value) == 250
    master.heartbeat_box.value = 700  # typed, not sent yet: the next frames leave it
    drawn(served)
    assert int(master.heartbeat_box.value) == 700
