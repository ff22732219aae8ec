"""The Drive tab names the drive's fieldbus state: the NMT state of a CANopen drive, the ESM
state of the drive on the EtherCAT line (seed 004 ch. 4, ch. 5; docs/dashboard.md).

A demo of the CANopen drive (static/scenarios/canopen_drive_alarm_reset.toml) focuses its
Drive tab, and the NMT state that its captions narrate ("the node goes to Operational") was on
the CANopen tab only.
"""

from __future__ import annotations

from pathlib import Path

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.drive.drive_state import state_rows
from app.ui.drive.view import bus_companions


def _rig(tmp_path: Path) -> Rig:
    return build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path)


def _rows(rig: Rig, drive: str) -> dict[str, str]:
    snapshot = rig.snapshot()
    devices = snapshot["devices"]
    node, slave = (devices.get(i) if i else None
                   for i in bus_companions(snapshot, drive))
    return dict(state_rows(devices[drive], node, slave))


def test_the_canopen_drive_shows_its_nmt_state(tmp_path: Path) -> None:
    rig = _rig(tmp_path)
    rig.run_until(500_000)  # booted: Pre-operational (ch. 4)
    assert "Pre-operational" in _rows(rig, "drive_co")["NMT state"]
    rig.devices["drive_co-can"].apply("frame", {"cob_id": 0x000, "data": "01 02"})
    rig.run_until(501_000)
    assert "Operational" in _rows(rig, "drive_co")["NMT state"]
    assert "Pre-operational" not in _rows(rig, "drive_co")["NMT state"]
    assert "ESM state" not in _rows(rig, "drive_co")


def test_the_ethercat_drive_shows_its_esm_state(tmp_path: Path) -> None:
    rig = _rig(tmp_path)
    rig.run_until(5_000_000)
    rows = _rows(rig, "drive_ec")
    esm = rig.snapshot()["devices"]["drive_ec-ecat"]["esm"]
    assert esm == "OP" and ">OP<" in rows["ESM state"]
    assert "NMT state" not in rows


def test_the_modbus_drive_has_no_fieldbus_state_row(tmp_path: Path) -> None:
    """Its CANopen node exists but is silent (c9 = Modbus): no NMT row, as no ESM row."""
    rig = _rig(tmp_path)
    rig.run_until(500_000)
    rows = _rows(rig, "drive")
    assert "NMT state" not in rows and "ESM state" not in rows
    assert list(rows)[:2] == ["CiA 402 state", "Mode"]
