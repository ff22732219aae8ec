"""served_dashboard.drawn waits for the dashboard thread to draw the current frame however
long a tick takes on a loaded machine (test_canopen_master_panel failed once under load).
It used to give the thread 200 simulation round trips (``advance(0)``), each publishing a new
frame that made the next tick a full one again: a tick slower than those round trips failed
the wait with "the dashboard did not draw the frame"."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from served_dashboard import drawn, served_default_rig

from app.screenshots import ServedRig
from app.ui.dashboard import Dashboard

SLOW_TICK_S = 0.5  # far longer than 200 round trips to an idle simulation thread


@pytest.fixture
def served() -> Iterator[ServedRig]:
    with served_default_rig(1.0) as live:
        yield live


def test_drawn_waits_for_a_slow_tick(served: ServedRig, monkeypatch: pytest.MonkeyPatch
                                     ) -> None:
    tick = Dashboard.tick

    def slow(dashboard: Dashboard) -> None:
        time.sleep(SLOW_TICK_S)  # as a starved dashboard thread
        tick(dashboard)

    monkeypatch.setattr(Dashboard, "tick", slow)
    before = served.runtime.frame.seq
    drawn(served)  # its advance publishes a frame after ``before``; a later one may follow
    assert served.dashboard.rendered_seq > before
