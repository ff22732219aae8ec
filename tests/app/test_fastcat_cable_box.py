"""The FastCAT's "EtherCAT cable in" box is the coupler's own plug at its IN port (the
operator's cable action), not the line's link: after the master pulls cable 0 the coupler has
no link, but its own cable is still in, and ticking the box could not bring the master's cable
back. Before, the box followed the link and went unticked, and ticking it did nothing."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from served_dashboard import drawn, served_default_rig
from test_reset_fault_control import box_shows

from app.screenshots import ServedRig


@pytest.fixture
def served() -> Iterator[ServedRig]:
    with served_default_rig(8.0) as live:
        yield live


def test_the_cable_box_is_the_coupler_s_own_plug(served: ServedRig) -> None:
    control = served.dashboard._panels.control  # type: ignore[union-attr]
    box = control._link
    served.command("master", "pull_cable", {"cable": 0})
    drawn(served)
    snap = served.runtime.frame.snapshot["devices"]["fastcat"]
    assert snap["link"] is False and snap["plugs"][0] is True
    box_shows(box, True)
    served.command("fastcat", "link", {"connected": False})
    drawn(served)
    box_shows(box, False)
    served.command("master", "plug_cable", {"cable": 0})
    drawn(served)
    box_shows(box, False)  # the master's cable is back, the coupler's own still out
    assert served.runtime.frame.snapshot["devices"]["fastcat"]["link"] is False
