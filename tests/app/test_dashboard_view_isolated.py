"""A view whose update raises does not stop the other views of the tick (app/ui/dashboard.py).

Before, one exception in a panel's update left the tick: every view after it (the Line tab,
the drive panels, the scenario player) kept its old values for as long as the panel kept
failing, and an instructor's table could wait for good (a CI timeout in
test_classroom_fault_forms had no other explanation left).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator

import pytest
from served_dashboard import ticked_dashboard

from app.ui.dashboard import Dashboard
from devices.events import Caption


@pytest.fixture
def dashboard() -> Iterator[Dashboard]:
    with ticked_dashboard() as dashboard:
        yield dashboard


def fresh_tick(dashboard: Dashboard, n: int) -> None:
    """A tick that has something new to draw: an event journalled as the simulation would."""
    dashboard.runtime._journal_events([Caption(0, "scenario", text=f"step {n}")])
    dashboard.tick()


def test_a_failing_panel_leaves_the_views_after_it_updating(
        dashboard: Dashboard, monkeypatch: pytest.MonkeyPatch,
        caplog: pytest.LogCaptureFixture) -> None:
    panels, line = dashboard._panels, dashboard._line
    assert panels is not None and line is not None

    def broken(*_args: object) -> None:
        raise RuntimeError("a view bug")

    lines: list[object] = []
    line_update = line.update
    monkeypatch.setattr(panels.state, "update", broken)
    monkeypatch.setattr(line, "update", lambda frame: (lines.append(frame), line_update(frame)))
    with caplog.at_level(logging.ERROR, logger="app.ui.dashboard"):
        for n in range(3):
            fresh_tick(dashboard, n)
    assert len(lines) == 3  # the Line tab, after the State panel, updated every tick
    assert dashboard._caption.text == "step 2"  # the caption too
    failures = [r for r in caplog.records if "state" in r.getMessage()]
    assert len(failures) == 1, [r.getMessage() for r in caplog.records]  # once, not per tick
    assert failures[0].exc_info is not None  # with its traceback


def test_a_panel_that_works_again_logs_its_next_failure(
        dashboard: Dashboard, monkeypatch: pytest.MonkeyPatch,
        caplog: pytest.LogCaptureFixture) -> None:
    panels = dashboard._panels
    assert panels is not None
    works = panels.state.update
    failing = [True]

    def flaky(*args: object) -> None:
        if failing[0]:
            raise RuntimeError("a view bug")
        works(*args)

    monkeypatch.setattr(panels.state, "update", flaky)
    with caplog.at_level(logging.ERROR, logger="app.ui.dashboard"):
        fresh_tick(dashboard, 0)
        failing[0] = False
        fresh_tick(dashboard, 1)
        failing[0] = True
        fresh_tick(dashboard, 2)
    assert len([r for r in caplog.records if "state" in r.getMessage()]) == 2
