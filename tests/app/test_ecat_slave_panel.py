"""The Slave tab of the drive's EtherCAT side names its PDO assignment as a technician writes
it. It showed Python lists, "Rx ['0x1600'] · Tx ['0x1A02']" (the snapshot's rx_assign and
tx_assign are lists of PDO indexes: 0x1C12 / 0x1C13). It had no 0x1001 row, which the CPX-E-EC's
Slave tab has."""

from __future__ import annotations

import re

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.line.slave_panel import slave_html


def _pdo_row(snap: dict) -> str:
    html = slave_html("drive_ec-ecat", {"kind": "servo_ecat", **snap})
    row = re.search(r"<th>PDO assignment</th><td>(.*?)</td>", html)
    assert row is not None
    return row.group(1)


def test_pdo_assignment_lists_the_indexes() -> None:
    row = _pdo_row({"rx_assign": ["0x1600"], "tx_assign": ["0x1A02", "0x1A03"]})
    assert row == "Rx 0x1600 · Tx 0x1A02, 0x1A03"


def test_an_empty_assignment_says_none() -> None:
    assert _pdo_row({"rx_assign": [], "tx_assign": []}) == "Rx none · Tx none"


def test_a_snapshot_without_the_keys_shows_a_dash() -> None:
    assert _pdo_row({}) == "Rx - · Tx -"


def _register_row(snap: dict) -> str:
    html = slave_html("drive_ec-ecat", {"kind": "servo_ecat", **snap})
    row = re.search(r"<th>Error register 0x1001</th><td>(.*?)</td>", html)
    assert row is not None, "the drive's Slave tab has no 0x1001 row"
    return row.group(1)


def test_the_error_register_reads_in_seed_004s_words() -> None:
    """Seed 004 ch. 5: the drive's CoE dictionary is its CANopen one, so 0x1001 names its bits
    as ch. 4's table does, in the form the CPX-E-EC's row has ("0x03 Generic Error, Current").
    """
    assert _register_row({"error_register": 0x21}) == "0x21 Generic Error, Device Profile Specific"
    assert _register_row({"error_register": 0}) == "0x00 no error"
    assert _register_row({}) == "0x00 no error"


def test_the_rigs_drive_shows_its_alarms_bits() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.devices["drive_ec"].apply("inject_alarm", {"code": "3"})  # 0x2310 overcurrent: bit 1
    for _ in range(50):
        rig.step()
    snap = rig.devices["drive_ec-ecat"].snapshot()
    assert _register_row(snap) == "0x03 Generic Error, Current"
