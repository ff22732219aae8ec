"""A newly promoted instructor's tables are written by the next redraw (docs/classroom.md "What
a trainee does not see"). Before: a copy built while the update thread showed new rows kept the
old ones (``RoleHtml.show`` / ``InstructorHtml.show`` skipped content they had shown), and a
redraw asked for while a tick was deciding was lost (``Dashboard._stale`` reset after it was
read, without a lock): on a paused rig nothing else redraws."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
import viser
from test_classroom_leak import TOKEN, Page, _wait

from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.line.master_panel import MasterPanel
from app.ui.panels.classroom_rig import serve_rig
from app.ui.panels.per_client import RoleHtml, instructor_for
from app.ui.style import INSTRUCTOR_CLASS


def _table(cause: str) -> str:
    return (f'<table><tr><th>ESM</th><td>OP</td></tr><tr class="{INSTRUCTOR_CLASS}">'
            f"<th>Injected</th><td>{cause}</td></tr></table>")


@pytest.fixture
def server() -> Iterator[viser.ViserServer]:
    server = viser.ViserServer(port=free_port(), verbose=False)
    try:
        yield server
    finally:
        server.stop()


def test_a_copy_built_during_an_update_is_written_by_the_redraw(
        server: viser.ViserServer) -> None:
    instructor = instructor_for(server, Access(TOKEN))
    html = RoleHtml(server, instructor, _table("0x04 old"), "causes")
    page = Page(server.get_port())
    cid, client = next(iter(_wait(lambda: server.get_clients()).items()))
    assert instructor.access.present(cid, TOKEN)
    (part,) = instructor._parts
    build = part._build

    def build_then_update(gui: Any) -> Any:  # the update thread shows new rows meanwhile
        built = build(gui)
        html.show(_table("0x0B new"))
        return built

    part._build = build_then_update  # type: ignore[method-assign]
    instructor.on_built = lambda: html.show(_table("0x0B new"))  # the redraw's tick
    try:
        instructor.promote(client)
        (copy,) = part.each()
        assert "0x0B new" in copy.content
    finally:
        page.close()


class _Frame:
    """A paused rig's frame whose second ``t_us`` read (the tick deciding) asks a redraw."""

    def __init__(self, frame: Any, redraw: Any) -> None:
        self.seq, self.snapshot, self._t_us = frame.seq, frame.snapshot, frame.t_us
        self._redraw, self._reads = redraw, 0

    @property
    def t_us(self) -> int:
        self._reads += 1
        if self._reads == 2:
            self._redraw()
        return self._t_us


def test_a_redraw_asked_during_a_tick_is_not_lost(monkeypatch: pytest.MonkeyPatch) -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    try:
        dashboard = served.dashboard
        dashboard.tick()  # the paused frame is drawn, its events taken: nothing new after it
        dashboard.tick()
        assert served.runtime.events_since(dashboard._event_seq)[1] == []
        assert dashboard._panels is not None
        drawn: list[int] = []
        monkeypatch.setattr(dashboard._panels.state, "update",
                            lambda *args: drawn.append(1))
        monkeypatch.setattr(served.runtime, "_frame",
                            _Frame(served.runtime.frame, dashboard._redraw))
        dashboard.tick()  # the redraw comes while this tick decides
        drawn.clear()
        dashboard.tick()
        assert drawn, "the redraw was lost"
    finally:
        served.stop()


def test_a_late_instructor_plug_type_starts_at_the_preset() -> None:
    """Seed 000 §2 (a module pulled and put back): Plug offers the type that belongs in the
    picked empty slot (test_module_plug_preset.py). An instructor promoted after the pick got
    a box at the catalog's first type (DB16): the preset was set on a pick or rail change
    only, for the copies there were then."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    try:
        served.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        served.runtime.advance(3_000_000).result(timeout=30)
        served.runtime.command("fastcat/3", "unplug", {}).result(timeout=10)
        served.runtime.advance(100_000).result(timeout=30)
        served.dashboard.tick()
        assert served.dashboard._panels is not None
        modules = served.dashboard._panels.modules
        assert "3 (empty)" in modules.pick.options
        modules.pick.set_all("3 (empty)")  # where the instructor's own picker starts
        page = Page(served.port)
        cid, client = next(iter(_wait(lambda: served.server.get_clients()).items()))
        assert served.classroom.access.present(cid, TOKEN)
        served.dashboard.instructor.promote(client)
        (form,) = modules._rails.each()
        assert form.plug_type.value == "DO16"
        page.close()
    finally:
        served.stop()


def test_the_line_master_panel_s_causes_reach_a_copy_built_during_an_update(
        server: viser.ViserServer) -> None:
    """The same race on the Line tab's master panel: its Injected / Causes rows (RoleHtml)
    were shown only when the status table changed, so the redraw's tick, with the same
    table, did not write the copy built meanwhile: the new instructor's page read no cause
    until the line changed again (on a paused rig, never)."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.advance(8000)
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.advance(200)
    master = rig.snapshot()["devices"]["master"]
    instructor = instructor_for(server, Access(TOKEN))
    panel = MasterPanel(server, None, "master")  # type: ignore[arg-type]  # no command sent
    page = Page(server.get_port())
    cid, client = next(iter(_wait(lambda: server.get_clients()).items()))
    assert instructor.access.present(cid, TOKEN)
    assert panel._status._causes is not None
    part = panel._status._causes._part
    build = part._build

    def build_then_update(gui: Any) -> Any:  # the update thread shows the causes meanwhile
        built = build(gui)
        panel.update(master, 0)
        return built

    part._build = build_then_update  # type: ignore[method-assign]
    instructor.on_built = lambda: panel.update(master, 0)  # the redraw's tick
    try:
        instructor.promote(client)
        (copy,) = part.each()
        assert "2: cable 2 pulled" in copy.content
    finally:
        page.close()


@pytest.mark.filterwarnings("error::UserWarning")
def test_a_page_that_left_gets_no_update_before_its_disconnect_callback() -> None:
    """viser marks a leaving page's widgets removed (no message: the connection is closed)
    before it runs the disconnect callbacks, and those run late on a loaded machine. Until
    Instructor._gone forgot the page, the frame update went on updating its copies: the Module
    faults form, restricted to the actions of the module read meanwhile, removed its parameter
    widgets a second time ("Attempted to remove an already removed GuiCheckboxHandle",
    action_form.py, seen in CI after test_a_late_instructor_plug_type_starts_at_the_preset)
    and built new ones on the closed connection."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    served.dashboard.stop()  # the frame updates are this test's own calls from here on
    try:
        served.dashboard.tick()
        assert served.dashboard._panels is not None
        faults = served.dashboard._panels.modules._faults
        assert faults is not None
        page = Page(served.port)
        cid, client = next(iter(_wait(lambda: served.server.get_clients()).items()))
        assert served.classroom.access.present(cid, TOKEN)
        instructor = served.dashboard.instructor
        instructor.promote(client)
        (copy,) = faults._part.each()
        form = copy.form
        assert form is not None and form.values(), "a fault action with parameters"
        _wait(lambda: copy.available is not None)  # module 1's actions, read at the build
        faults.update(False)
        with instructor._lock:  # Instructor._gone waits: the disconnect callback is late
            page.close()
            _wait(lambda: not served.server.get_clients())
            _wait(lambda: form.choice._impl.removed)  # viser let the page's widgets go
            faults._park(copy, copy.asked, [])  # the picked module's actions, read meanwhile: none
            faults.update(False)  # a frame update in that window
            assert form.options() != ("(none)",)  # the gone page's form left alone
        _wait(lambda: not faults._part.each())
    finally:
        served.stop()
