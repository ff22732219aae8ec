"""The Slave tab of the drive's EtherCAT side names its PDO assignment as a technician writes
it. It showed Python lists, "Rx ['0x1600'] · Tx ['0x1A02']" (the snapshot's rx_assign and
tx_assign are lists of PDO indexes: 0x1C12 / 0x1C13)."""

from __future__ import annotations

import re

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
