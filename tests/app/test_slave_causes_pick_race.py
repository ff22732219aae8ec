"""The instructor's Slave causes table ends on the causes of the slave its own picker names,
whichever of its two writers comes last (app/ui/line/slave_panel.py): the pick's callback
(viser's thread pool) and the dashboard's frame update (its own thread).

Each read the pick and the frame, then wrote, unguarded: the dashboard could write the causes
of the pick before the new one over the callback's, or the callback the causes of the frame
before the new one over the dashboard's. viser keeps only the newest pending update of a
widget's property, so the right content may never have reached the page, and the table stayed
wrong until the next frame: 1/30 s later on an idle rig (the simulation thread publishes one
every 1/30 s, paused or not), as long as a busy simulation thread takes otherwise (a long
advance, a catch-up). Each test holds one writer between its read and its write while the
other writes, with no frame to put it right (the simulation thread held), as a loaded machine
can.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from test_classroom_leak import Page, _wait, open_class

from app.classroom.roles import Role
from app.ui.line import slave_panel
from app.ui.panels.classroom_rig import ServedRig

DASHBOARD = "fieldrig-dashboard"  # the dashboard thread's name (Dashboard.start)
HOLD_S = 10.0


@pytest.fixture
def served() -> Iterator[tuple[ServedRig, Page]]:
    with open_class() as (live, _trainee, instructor):
        yield live, instructor


def _instructor_id(live: ServedRig) -> int:
    return next(c for c in live.server.get_clients()
                if live.classroom.access.role(c) is Role.INSTRUCTOR)


def _panel(live: ServedRig) -> Any:
    line = live.dashboard.line
    assert line is not None
    return line.slave


def _picker_and_table(live: ServedRig, page: Page) -> tuple[str, str]:
    """The uuids of the instructor's own Slave causes picker and table, once its page has
    them."""
    def found() -> tuple[str, str] | None:
        got = page.received()
        folder = next((m["uuid"] for m in got if m.get("type") == "GuiFolderMessage"
                       and (m.get("props") or {}).get("label") == "Slave causes"), None)
        inside = [m for m in got if folder is not None and m.get("container_uuid") == folder]
        picker = next((m["uuid"] for m in inside if m["props"].get("label") == "Slave"), None)
        table = next((m["uuid"] for m in inside if m.get("type") == "GuiHtmlMessage"), None)
        return (picker, table) if picker and table else None

    return _wait(found)


def _shown(page: Page, table: str) -> str:
    """What the page shows in the table now: its newest content."""
    contents = [str((m.get("updates") or m.get("props") or {}).get("content"))
                for m in page.received() if m.get("uuid") == table
                and "content" in (m.get("updates") or m.get("props") or {})]
    return contents[-1] if contents else ""


def _short(live: ServedRig, on: bool) -> None:
    action = "inject_fault" if on else "clear_fault"
    live.runtime.submit(lambda: live.rig.apply(
        "cpx/2", action, {"fault": "short_circuit", "channel": 3})).result(timeout=10)
    live.runtime.advance(10_000).result(timeout=30)  # a new frame: the dashboard writes


def _settled(live: ServedRig) -> None:
    """The dashboard has drawn the newest frame (its tick is done)."""
    seq = live.runtime.frame.seq
    _wait(lambda: live.dashboard.rendered_seq >= seq)


class _NoFrames:
    """The simulation thread held (queued work that waits) until :meth:`end`: it publishes
    only the frames :meth:`publish` asks for."""

    def __init__(self, live: ServedRig) -> None:
        self._live = live
        self._go, self._ask, self._asked = threading.Event(), threading.Event(), threading.Event()
        held = threading.Event()

        def hold() -> None:
            held.set()
            while not self._go.is_set():
                if self._ask.wait(0.01):
                    self._ask.clear()
                    live.runtime._publish()
                    self._asked.set()

        self._done = live.runtime.submit(hold)
        assert held.wait(HOLD_S), "the simulation thread did not take the work"

    def publish(self) -> None:
        self._asked.clear()
        self._ask.set()
        assert self._asked.wait(HOLD_S), "no frame published"

    def end(self) -> None:
        self._go.set()
        self._done.result(timeout=HOLD_S)


class _HeldHtml:
    """The table as one thread sees it: once ``armed``, that thread's next look at it (after
    it read the pick, before it writes) waits for ``release``."""

    def __init__(self, real: Any, thread: Callable[[], bool]) -> None:
        self._real, self._thread = real, thread
        self.armed, self.entered, self.release = False, threading.Event(), threading.Event()

    @property
    def content(self) -> str:
        if self.armed and self._thread():
            self.armed = False
            self.entered.set()
            assert self.release.wait(HOLD_S), "never released"
        return str(self._real.content)

    @content.setter
    def content(self, value: str) -> None:
        self._real.content = value


def _on_dashboard() -> bool:
    return threading.current_thread().name == DASHBOARD


def test_a_pick_during_a_frame_update_is_not_undone_by_it(
    served: tuple[ServedRig, Page],
) -> None:
    """The dashboard read the picker (trscat), the pick of cpx came and its callback wrote
    cpx's causes, then the dashboard wrote trscat's over them."""
    live, instructor = served
    panel = _panel(live)
    picker, table = _picker_and_table(live, instructor)
    _short(live, True)
    _settled(live)
    client_id = _instructor_id(live)
    form = panel._causes.of(client_id)
    assert form is not None and form.picker.value == "trscat"
    # The dashboard's copy of the form: the same picker, a table whose writes it holds.
    held = _HeldHtml(form.html, _on_dashboard)
    panel._causes._built[client_id] = slave_panel._Causes(form.picker, held)
    frames = _NoFrames(live)
    _settled(live)  # no update under way: the next is the one of the frame below
    held.armed = True
    try:
        frames.publish()
        assert held.entered.wait(HOLD_S), "the dashboard did not update the table"
        instructor.set(picker, "cpx")
        time.sleep(0.5)  # the pick's callback runs meanwhile
    finally:
        held.release.set()
    try:
        _settled(live)  # the dashboard's update of that frame is done
        # No frame comes to put it right: a stale write stays, and this times out.
        _wait(lambda: "short 3" in str(form.html.content))
        _wait(lambda: "short 3" in _shown(instructor, table))
    finally:
        frames.end()
    _short(live, False)

def test_a_frame_during_a_pick_is_not_undone_by_its_callback(
    served: tuple[ServedRig, Page],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The pick's callback read the frame before the short was wired, the dashboard wrote the
    frame with it, then the callback wrote the causes without it."""
    live, instructor = served
    picker, table = _picker_and_table(live, instructor)
    _settled(live)
    panel = _panel(live)
    entered, release, written = threading.Event(), threading.Event(), threading.Event()
    drawn, shown, callback = slave_panel.slave_html, panel._show, threading.local()

    def show(form: Any) -> None:  # this panel's, from a pick's callback (not another rig's)
        callback.mine = not _on_dashboard()
        try:
            shown(form)
        finally:
            if callback.mine and entered.is_set():
                written.set()
            callback.mine = False

    def held_html(device: str, snap: Any) -> str:
        if device == "cpx" and getattr(callback, "mine", False) and not entered.is_set():
            entered.set()  # what the callback read is fixed, its write is to come
            assert release.wait(HOLD_S), "never released"
        return drawn(device, snap)

    monkeypatch.setattr(panel, "_show", show)
    monkeypatch.setattr(slave_panel, "slave_html", held_html)
    form = panel._causes.of(_instructor_id(live))
    assert form is not None
    instructor.set(picker, "cpx")
    assert entered.wait(HOLD_S), "the pick's callback did not run"
    try:
        _short(live, True)  # a frame with the short: the dashboard updates
        frames = _NoFrames(live)
        time.sleep(0.5)  # the dashboard's update of that frame runs meanwhile
    finally:
        release.set()
    try:
        assert written.wait(HOLD_S), "the pick's callback did not finish"
        # No frame comes to put it right: a stale write stays, and this times out.
        _wait(lambda: "short 3" in str(form.html.content))
        _wait(lambda: "short 3" in _shown(instructor, table))
    finally:
        frames.end()
    _short(live, False)


def test_a_pick_in_the_shared_picker_shows_its_causes_at_once(
    served: tuple[ServedRig, Page],
) -> None:
    """The instructor's Slave causes picker follows its page's pick in the Slave tab
    (SlavePanel._follow): viser runs the picker's callback on that assignment, which writes
    the table under the lock, with no frame to wait for (and no lock held around it)."""
    live, instructor = served
    _picker_and_table(live, instructor)
    _short(live, True)
    _settled(live)
    form = _panel(live)._causes.of(_instructor_id(live))
    assert form is not None and "short 3" not in str(form.html.content)
    frames = _NoFrames(live)
    try:
        instructor.set(instructor.widget("Slave", "trscat"), "cpx")  # the shared picker
        _wait(lambda: form.picker.value == "cpx")
        _wait(lambda: "short 3" in str(form.html.content))
    finally:
        frames.end()
    _short(live, False)
