"""The drive's fieldbus state in the Drive tab's rows: the NMT state of its CANopen node, the
ESM state of its EtherCAT (CoE) slave.

Both come from the companion models' snapshots (devices/canopen/node.py ``nmt``,
devices/coe/drive_slave.py ``esm``): a demo that focuses a CANopen drive's Drive tab narrates
"the node goes to Operational", which only the CANopen tab showed before (docs/dashboard.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from app.ui.line.slave_panel import esm_badge
from app.ui.style import badge, esc
from devices.ethercat import describe_al_status_code

NMT_TONE = {"Operational": "ok", "Pre-operational": "warn", "Stopped": "bad"}


def nmt_badge(state: str) -> str:
    return badge(state, NMT_TONE.get(state, "muted"))


def fieldbus_rows(drive: Mapping[str, Any], node: Mapping[str, Any] | None,
                  slave: Mapping[str, Any] | None) -> list[tuple[str, str]]:
    """"NMT state" while the drive speaks CANopen (its node is silent on another fieldbus,
    c9), "ESM state" when the drive is on the EtherCAT line."""
    rows = []
    if node and (node.get("active") or drive.get("fieldbus") == "canopen"):
        rows.append(("NMT state", nmt_badge(str(node.get("nmt", "Off")))))
    if slave:
        code = int(slave.get("al_status_code", 0))
        text = esm_badge(slave)
        if code:
            text += esc(f" · AL status code 0x{code:04X} "
                        f"{slave.get('al_status_text') or describe_al_status_code(code)}")
        rows.append(("ESM state", text))
    return rows
