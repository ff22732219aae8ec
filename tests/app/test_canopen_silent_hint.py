"""The CANopen tab of a drive not on CANopen points at the drive that is (docs/dashboard.md
"The CANopen tab and the master").

A trainee following README's "Talking to the drive over CANopen" (drive_co, node 2) opened the
CANopen tab of the default rig and read "drive-can · node 1 · CANopen is silent: the drive
speaks Modbus RTU ... Set c9 = 5 (CANopen), save to flash and switch the drive off and on":
the tab shows the drive picked in *Servo drive* (the Modbus one first), and its note sent the
trainee to reconfigure that drive while drive_co was on CANopen all along.
"""

from __future__ import annotations

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.drive.canopen_panel import on_canopen, status_html
from app.ui.drive.view import bus_companions


def _silent_note(drive: str) -> str:
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    rig.run_until(500_000)  # drive_co's node has booted (seed 004 ch. 4)
    snapshot = rig.snapshot()
    devices = snapshot["devices"]
    nodes = {d: bus_companions(snapshot, d)[0] or "" for d in ("drive", "drive_co", "drive_ec")}
    node = nodes[drive]
    return status_html(node, devices[node], devices[drive], on_canopen(devices, nodes))


def test_the_modbus_drives_tab_names_the_drive_on_canopen() -> None:
    html = _silent_note("drive")
    assert "CANopen is silent: the drive speaks Modbus RTU (c9 read at power-up)." in html
    assert "drive_co is on CANopen (node 2): pick it in Servo drive." in html
    assert "Or set c9 = 5 (CANopen)" in html


def test_no_pointer_when_no_drive_is_on_canopen() -> None:
    html = status_html("drive-can", {"active": False, "bitrate": 500000},
                       {"powered": True, "fieldbus": "modbus"}, [])
    assert "pick it in Servo drive" not in html and "Set c9 = 5 (CANopen)" in html


def test_the_canopen_drive_is_not_pointed_at_itself() -> None:
    html = _silent_note("drive_co")  # active: its status table, no note
    assert "CANopen is silent" not in html and "pick it in" not in html
