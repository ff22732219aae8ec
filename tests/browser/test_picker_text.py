"""The closed Fault and drive Alarm boxes show their longest option whole at 1280x720: the
options are "0x0B UNKNOWN_SDO_WR_ANSWER"-style code + manual name, and the box cut the last
characters of the longest ones (the list and the hint showed them whole)."""

from __future__ import annotations

from typing import Any

import pytest
from helpers import LiveDashboard, choose, open_dashboard, wait_until

from app.ui.dashboard import fault_options
from app.ui.drive.drive_options import alarm_options
from devices.servo.parameters import C9_BY_FIELDBUS

pytestmark = pytest.mark.browser

CLIPPED_JS = "e => e.scrollWidth > e.clientWidth ? [e.scrollWidth, e.clientWidth] : null"


def _longest(options: Any) -> str:
    return max(options, key=len)


def _shown_whole(page: Any, label: str, value: str) -> None:
    box = page.get_by_label(label, exact=True).first
    wait_until(lambda: box.input_value() == value, what=f"{label} showing {value}")
    clipped = box.evaluate(CLIPPED_JS)
    assert clipped is None, f"{label} box cuts {value!r}: text {clipped[0]} px in {clipped[1]} px"


def test_longest_fault_and_alarm_names_fit_the_closed_box(live: LiveDashboard, page: Any
                                                          ) -> None:
    panels = live.dashboard._panels
    drives = live.dashboard.drives
    assert panels is not None and drives is not None
    open_dashboard(page, live)
    for table, label in (("coupler", "coupler codes (§7.5)"), ("module", "module codes (§7.6)")):
        choose(page, "Table", label)  # the page's own pick (an open rig's: ClientPick)
        longest = _longest(f.label for f in fault_options() if f.table == table)
        choose(page, "Fault", longest)
        _shown_whole(page, "Fault", longest)
    page.get_by_role("tab", name="Servo drive", exact=True).first.click()
    drive = live.rig.device("drive")  # the page's picked drive (the Modbus one)
    for fieldbus in ("ethercat", "profinet"):
        # Each page's Alarm list is its own drive's (an open rig's ClientPick): the drive is
        # put on ``fieldbus`` as a power-up with that c9 would (ch. 2), and the page picks
        live.runtime.submit(lambda bus=fieldbus: drive.latched_at_power_up.__setitem__(
            "c9", C9_BY_FIELDBUS[bus])).result(timeout=10)
        live.advance(0.2)
        offered = alarm_options(fieldbus)
        longest = _longest(offered)
        wait_until(lambda offered=offered: page.get_by_label(
            "Alarm", exact=True).first.input_value() in offered, what=f"the {fieldbus} alarms")
        choose(page, "Alarm", longest)
        _shown_whole(page, "Alarm", longest)
