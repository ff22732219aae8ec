"""A page that closes while its widgets are being built (docs/classroom.md "What a trainee
does not see").

viser drops a client from ``get_clients()`` and unhooks its elements from the server's
containers before its disconnect callbacks run; whatever is built for it after that lands in
those containers for good, and a client folder it had is gone (``KeyError`` from
``_resolve_container_handle``). Before: the instructor's parts kept the gone connection (the
update thread wrote to its dead handles every tick) and a trainee page closed during its
connect build logged a traceback. Two websocket connections stand in for the browsers."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
import viser
from test_classroom_leak import TOKEN, Page, _wait

from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.panels import classroom as classroom_module
from app.ui.panels.classroom import ClassroomPanel
from app.ui.panels.classroom_rig import ServedRig, serve_rig


@pytest.fixture
def served() -> Iterator[ServedRig]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    try:
        yield served
    finally:
        served.stop()


def _left(page: Page, served: ServedRig, client_id: int) -> None:
    page.close()
    _wait(lambda: client_id not in served.server.get_clients())
    time.sleep(0.3)  # viser's disconnect callbacks (its thread pool) have had their time


def _in_server_containers(client: viser.ClientHandle) -> int:
    """The client's elements still hooked into server containers (none once it is gone)."""
    return len(client.gui._handles_in_foreign_containers)


def test_a_page_gone_while_promoted_keeps_no_instructor_part(served: ServedRig) -> None:
    page = Page(served.port)
    clients = _wait(lambda: served.server.get_clients())
    cid, client = next(iter(clients.items()))
    _wait(lambda: cid in served.classroom._views)  # its connect build is over
    instructor = served.dashboard.instructor
    built: list[int] = []
    instructor.on_built = lambda: built.append(cid)
    assert served.classroom.access.present(cid, TOKEN)
    first = instructor._parts[0]
    build_for = first.build_for

    def leave_then_build(c: viser.ClientHandle) -> None:  # the role was checked already
        _left(page, served, cid)
        build_for(c)

    first.build_for = leave_then_build  # type: ignore[method-assign]
    instructor.promote(client)
    assert [p for p in instructor._parts if cid in p._built] == []
    assert built == []  # no redraw for a page that is not there
    assert _in_server_containers(client) == 0


def test_a_page_gone_during_its_connect_build_logs_nothing(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The connect callback ran in viser's pool: its KeyError was printed as a traceback."""
    pages: list[Page] = []
    servers: list[ServedRig] = []
    failures: list[BaseException] = []
    done: list[viser.ClientHandle] = []
    connect, trainee_html = ClassroomPanel._connect, classroom_module.trainee_html

    def recording_connect(self: ClassroomPanel, client: viser.ClientHandle) -> None:
        try:
            connect(self, client)
        except BaseException as exc:
            failures.append(exc)
            raise
        finally:
            done.append(client)

    left = threading.Event()

    def leave(*args: Any, **kwargs: Any) -> str:  # inside the "Exercise" folder being built
        if not left.is_set():
            left.set()
            page, served = _wait(lambda: pages and pages[0]), servers[0]
            _left(page, served, next(iter(served.server.get_clients())))
        return trainee_html(*args, **kwargs)

    # Registered at construction: the patched callback is the one the server calls.
    monkeypatch.setattr(ClassroomPanel, "_connect", recording_connect)
    monkeypatch.setattr(classroom_module, "trainee_html", leave)
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    servers.append(serve_rig(rig, Access(TOKEN), port=free_port(), paused=True))
    try:
        pages.append(Page(servers[0].port))
        client = _wait(lambda: done and done[0])
        assert failures == []
        assert servers[0].classroom._views == {}
        assert _in_server_containers(client) == 0
    finally:
        servers[0].stop()
