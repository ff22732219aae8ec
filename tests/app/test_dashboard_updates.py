"""What the dashboard sends, and when (docs/dashboard.md "Threading"; issue 7 benchmark 2).

- The state panel's title line (box, station, simulated time) and its table are separate
  handles: a frame that only moves the time rewrites the title, not the table; a changed value
  rewrites the table (seed 000 §2: the CNF row turns "pressed" while the button is held).
- The update thread ticks on each frame the runtime publishes, not on its own period.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from app.ui import dashboard as dashboard_module
from app.ui.panels.state import StatePanel

SNAP: dict[str, Any] = {"id": "fastcat", "station_address": 1001, "esm": "OP", "powered": True,
                        "cnf": {"phase": "idle"}, "scan": {}}


class _Html:
    def __init__(self, content: str) -> None:
        self._content = content
        self.writes: list[str] = []

    @property
    def content(self) -> str:
        return self._content

    @content.setter
    def content(self, value: str) -> None:
        self._content = value
        self.writes.append(value)


class _Gui:
    def __init__(self) -> None:
        self.handles: list[_Html] = []

    def add_html(self, content: str) -> _Html:
        self.handles.append(_Html(content))
        return self.handles[-1]


class _Server:
    def __init__(self) -> None:
        self.gui = _Gui()


def _panel() -> tuple[StatePanel, _Html, _Html]:
    server = _Server()
    panel = StatePanel(server)  # type: ignore[arg-type]
    title, table = server.gui.handles
    return panel, title, table


def test_title_is_above_the_table() -> None:
    _, title, table = _panel()
    assert title.content == ""  # nothing before the first frame
    assert 'id="fr-state"' in table.content


@pytest.mark.parametrize("t_us", [1_100_000, 5_000_000, 61_300_000])
def test_time_alone_rewrites_the_title_only(t_us: int) -> None:
    panel, title, table = _panel()
    panel.update(SNAP, None, 1_000_000)
    panel.update(SNAP, None, t_us)
    assert len(table.writes) == 1
    assert len(title.writes) == 2 and f"t = {t_us // 100_000 / 10:.1f} s" in title.writes[-1]


def test_same_tenth_of_a_second_sends_nothing() -> None:
    panel, title, table = _panel()
    panel.update(SNAP, None, 1_000_000)
    panel.update(SNAP, None, 1_099_999)
    assert (len(title.writes), len(table.writes)) == (1, 1)


def test_a_changed_value_rewrites_the_table() -> None:
    """Seed 000 §2: CNF held -> the CNF row shows "pressed"."""
    panel, _title, table = _panel()
    panel.update(SNAP, None, 1_000_000)
    panel.update({**SNAP, "cnf": {"phase": "idle", "pressed": True, "held_s": 0.0}}, None,
                 1_000_000)
    assert len(table.writes) == 2 and ">pressed 0.0 s<" in table.writes[-1]


def test_update_thread_ticks_on_published_frames(monkeypatch: pytest.MonkeyPatch) -> None:
    """With a period far beyond the test, only the runtime's frames can make it tick."""
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.screenshots import ServedRig

    monkeypatch.setattr(dashboard_module, "UPDATE_HZ", 1e-6)
    served = ServedRig.start(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    try:
        ticked = threading.Event()
        tick = served.dashboard.tick

        def tick_and_tell() -> None:
            tick()
            ticked.set()
        served.dashboard.tick = tick_and_tell  # type: ignore[method-assign]
        served.runtime.advance(100_000).result(timeout=30)
        assert ticked.wait(timeout=30), "the update thread did not tick on a frame"
        seq = served.runtime.frame.seq
        ticked.clear()
        assert ticked.wait(timeout=30)
        assert served.dashboard.rendered_seq >= seq
    finally:
        served.stop()


def test_rendered_seq_moves_only_once_the_views_are_written() -> None:
    """A reader waiting on rendered_seq (tests, the screenshot tool) then reads the widgets:
    during a tick the new frame must not be announced yet. It was, at the tick's start, and
    test_cpx_switch_form read the Line tab's form before the tick had reached it."""
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.screenshots import ServedRig

    served = ServedRig.start(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    try:
        line = served.dashboard.line
        assert line is not None
        seen: list[tuple[int, int]] = []
        update = line.update

        def update_and_look(frame: Any) -> None:
            seen.append((frame.seq, served.dashboard.rendered_seq))
            update(frame)
        line.update = update_and_look  # type: ignore[method-assign]
        served.advance(0.01)
        seq = served.runtime.frame.seq
        deadline = time.monotonic() + 30
        while served.dashboard.rendered_seq < seq and time.monotonic() < deadline:
            time.sleep(0.01)
        assert served.dashboard.rendered_seq >= seq, "the dashboard did not draw the frame"
        assert seen, "the Line view was not updated"
        assert all(announced < drawn for drawn, announced in seen), seen
    finally:
        served.stop()
