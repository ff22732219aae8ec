"""The panels' titles keep "t = 116.3 s" on one line.

The Drive tab's title of the Modbus drive is long ("drive · Modbus RTU node 1 · served as
Modbus TCP on :46669 · t = 116.3 s"): in the 400 px left panel it broke inside the time, "· t"
at the end of the first line and "= 116.3 s" under it (the dashboard at 1280 x 720). The time
is one unit in every title (the FastCAT's State tab, the master's Line tab, the Drive tab),
as the scenario player's status already keeps it.
"""

from __future__ import annotations

import re

from app.modbus.line import ServedLine
from app.ui.drive.drive_state import title as drive_title
from app.ui.line.master_panel import title as master_title
from app.ui.panels.state import title as state_title
from app.ui.style import CSS

T_US = 116_300_000


def nowrap_classes() -> set[str]:
    """The classes the dashboard's CSS keeps on one line."""
    rules = re.findall(r"([^{}]+)\{([^}]*)\}", CSS)
    return {name for selector, body in rules if "white-space: nowrap" in body
            for name in re.findall(r"^\s*\.([\w-]+)\s*$", selector)}


def clock_is_one_unit(html: str) -> None:
    spans = re.findall(r'<span class="([^"]*)">(t = [^<]*)</span>', html)
    assert spans, html
    for classes, text in spans:
        assert set(classes.split()) & nowrap_classes(), f"{text!r} may wrap: {html}"
        assert text == "t = 116.3 s"


def test_the_drive_title_keeps_its_time_on_one_line() -> None:
    served = ServedLine("socket", 46669)
    snap = {"fieldbus": "modbus", "node_id": 1}
    html = drive_title("drive", snap, T_US, modbus=served)
    assert "served as Modbus TCP on :46669" in html
    clock_is_one_unit(html)


def test_the_state_and_master_titles_too() -> None:
    clock_is_one_unit(state_title({"station_address": 1001, "id": "fastcat"}, None, T_US))
    clock_is_one_unit(master_title({"id": "master"}, T_US))
