"""The dashboard resends the pages' own picks at every tick (app/ui/panels/client_pick.py
resend_overwritten), not only when a frame comes."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from served_dashboard import drawn, served_default_rig

from app.screenshots import ServedRig
from app.ui import dashboard as dashboard_module


@pytest.fixture
def served() -> Iterator[ServedRig]:
    with served_default_rig(1.0) as live:
        yield live


def test_each_tick_resends_the_picks_a_broadcast_overwrote(served: ServedRig,
                                                           monkeypatch: pytest.MonkeyPatch
                                                           ) -> None:
    """A paused rig publishes no frame after an Unplug's: the pages' own picks must still
    come back (tests/browser/test_picks_two_pages.py), so every tick resends, not only the
    Module panel's update on a new frame."""
    calls: list[object] = []
    monkeypatch.setattr(dashboard_module, "resend_overwritten", calls.append)
    drawn(served)
    seq = served.runtime.frame.seq
    calls.clear()
    served.dashboard.tick()  # no new frame (the dashboard thread's own ticks may add calls)
    assert served.runtime.frame.seq == seq
    assert calls and all(server is served.server for server in calls)
