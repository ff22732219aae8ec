"""A view whose write to viser failed sends it at the next tick (docs/dashboard.md
"Threading").

A review's log had "dashboard view 'line' failed to update ... deque mutated during
iteration" (viser 1.1.1's push() off its loop, app/ui/viser_event.py). The rest of that view's
writes were skipped, and before:
- on a rig whose frame did not move (paused) no later tick ran the view again: what it
  skipped stayed unsent until the frame moved;
- a cable being redrawn (pulled) had its new state recorded before its boxes were sent: the
  next ticks saw it drawn and the page kept half a cable until it was plugged again.
Each test compares with a twin dashboard that took the same frames without the failure.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from typing import Any

import pytest
from twin_dashboards import differing, failing_write, step, twin

from app.ui.dashboard import Dashboard
from app.ui.line import master_panel
from app.ui.panels import event_log

BOOT_STEPS = 5000  # the line in OP


@pytest.fixture
def twins() -> Iterator[tuple[Dashboard, Dashboard]]:
    with twin(BOOT_STEPS) as reference, twin(BOOT_STEPS) as failing:
        assert differing(reference, failing) == []
        yield reference, failing


def in_line_update(dashboard: Dashboard, monkeypatch: pytest.MonkeyPatch) -> list[bool]:
    """A flag that is set while the Line view updates."""
    line = dashboard.line
    assert line is not None
    inside, update = [False], line.update

    def watched(*args: Any) -> None:
        inside[0] = True
        try:
            update(*args)
        finally:
            inside[0] = False

    monkeypatch.setattr(line, "update", watched)
    return inside


def test_a_failed_view_is_updated_again_on_the_same_frame(
        twins: tuple[Dashboard, Dashboard], monkeypatch: pytest.MonkeyPatch,
        caplog: pytest.LogCaptureFixture) -> None:
    reference, failing = twins
    inside = in_line_update(failing, monkeypatch)
    for board in twins:
        step(board, 300)
    reference.tick()
    with caplog.at_level(logging.ERROR, logger="app.ui.dashboard"), \
            failing_write(failing, lambda _message: inside[0]) as failed:
        failing.tick()  # the Line view's first write fails, its others are skipped
    assert failed and "'line' failed to update" in caplog.text
    assert differing(reference, failing) != []
    failing.tick()  # the same frame: a paused rig publishes no other
    assert differing(reference, failing) == []


def test_a_cable_whose_drawing_failed_is_drawn_again(
        twins: tuple[Dashboard, Dashboard]) -> None:
    reference, failing = twins
    for board in twins:
        board.runtime.rig.apply("master", "pull_cable", {"cable": 1})
        step(board, 300)
    reference.tick()
    with failing_write(failing, lambda m: getattr(m, "name", "") == "/line/cable1/seg1") \
            as failed:
        failing.tick()  # half of cable 1 redrawn red
    assert failed
    for board in twins:
        step(board, 1)
        board.tick()
    assert differing(reference, failing) == []


@pytest.mark.parametrize(("module", "renderer"), [
    (master_panel, "log_table"),  # the Line tab's master log
    (event_log, "render_rows"),  # the State tab's event log, the master's lines in it
])
def test_a_log_that_failed_to_render_is_sent_at_the_next_tick(
        twins: tuple[Dashboard, Dashboard], monkeypatch: pytest.MonkeyPatch, module: Any,
        renderer: str) -> None:
    """The log's signature was recorded before its table was rendered and written: the
    retry found it unchanged and the page kept the old log until the master's next line."""
    reference, failing = twins
    for board in twins:
        board.runtime.rig.apply("master", "pull_cable", {"cable": 1})  # the master logs it
        step(board, 300)
    reference.tick()
    render = getattr(module, renderer)

    def broken(*_args: Any) -> str:
        raise RuntimeError("a renderer bug")

    monkeypatch.setattr(module, renderer, broken)
    failing.tick()
    assert differing(reference, failing) != []
    monkeypatch.setattr(module, renderer, render)
    failing.tick()
    assert differing(reference, failing) == []
