"""ClientSynced (app/ui/panels/client_input.py): the drive controls of a rig with several
drives, where each page shows the model's value of its own pick.

viser 1.1.1's page sends its GUI changes through one sender throttled to 50 ms that keeps the
latest message of any widget (docs/dashboard.md "Fast clicks"): a Power click followed within
the window by a click elsewhere never reaches the server while the page shows the box
checked. Synced sends the model's value again on the page's next message; the per-page
ClientSynced must too, or that page shows a drive powered that is not.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator
from types import SimpleNamespace
from typing import Any

import pytest
from fake_viser import Pages
from own_loop import complete
from viser._messages import GuiUpdateMessage

from app.ui.panels import client_input
from app.ui.panels.client_input import ClientSynced


class _Server:
    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._websock_server = Pages(loop)
        # Every page already has the replay of the shared elements (client_pick.page_ready).
        self._websock_server._broadcast_buffer = SimpleNamespace(  # type: ignore[attr-defined]
            message_counter=1, generator_cursors={1: 5, 2: 5})
        self.clients = {1: SimpleNamespace(client_id=1), 2: SimpleNamespace(client_id=2)}

    def get_event_loop(self) -> asyncio.AbstractEventLoop:
        return self._loop

    def get_clients(self) -> dict[int, Any]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Callable[[Any], None]) -> None:
        return None


class _Runtime:
    def __init__(self) -> None:
        self.work: list[Callable[[], None]] = []
        self.commands: list[tuple[int, Any]] = []

    def command(self, client: Any, value: Any) -> None:
        self.commands.append((client.client_id, value))

    def submit(self, client: Any, label: str, fn: Callable[[], Any], *,
               done: Callable[[Any], None] | None = None) -> None:
        self.work.append(lambda: done(fn()) if done is not None else fn())

    def drain(self) -> None:
        work, self.work = self.work, []
        for fn in work:
            fn()


@pytest.fixture
def loop() -> Iterator[asyncio.AbstractEventLoop]:
    loop = asyncio.new_event_loop()
    yield loop
    loop.close()


@pytest.fixture
def sent(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, Any]]:
    out: list[tuple[int, Any]] = []
    monkeypatch.setattr(client_input, "send_to",
                        lambda client, uuid, prop, value: out.append((client.client_id, value)))
    return out


def _power(loop: asyncio.AbstractEventLoop) -> tuple[_Server, _Runtime, ClientSynced]:
    server = _Server(loop)
    runtime = _Runtime()
    handle = SimpleNamespace(_impl=SimpleNamespace(uuid="power", value=False, sync_cb=1))
    synced = ClientSynced(server, handle, runtime, runtime.command)  # type: ignore[arg-type]
    return server, runtime, synced


def _frame(loop: asyncio.AbstractEventLoop, synced: ClientSynced, model: bool = False) -> None:
    """A dashboard frame: ``model`` is page 1's drive's value, page 2's drive stays off."""
    synced.follow_each(lambda client_id: model if client_id == 1 else False)
    complete(loop, asyncio.sleep(0))


def test_a_click_the_page_never_sent_goes_back_at_its_next_message(
        loop: asyncio.AbstractEventLoop, sent: list[tuple[int, Any]]) -> None:
    server, runtime, synced = _power(loop)
    _frame(loop, synced)
    assert sorted(sent) == [(1, False), (2, False)]
    sent.clear()
    # page 1: Power checked (dropped by its sender), then another widget's change (sent)
    server._websock_server.message(1, GuiUpdateMessage("mode", {"value": "1"}))
    _frame(loop, synced)
    assert sent == [(1, False)]  # page 1's box back to its drive's model; page 2 untouched
    _frame(loop, synced)
    assert sent == [(1, False)] and runtime.commands == []


def test_a_pages_message_does_not_undo_its_change_on_its_way(
        loop: asyncio.AbstractEventLoop, sent: list[tuple[int, Any]]) -> None:
    server, runtime, synced = _power(loop)
    _frame(loop, synced)
    sent.clear()
    server._websock_server.message(1, GuiUpdateMessage("power", {"value": True}))
    server._websock_server.message(1, GuiUpdateMessage("mode", {"value": "1"}))
    _frame(loop, synced)
    assert sent == [] and runtime.commands == [(1, True)]  # the click stays shown
    runtime.drain()
    complete(loop, asyncio.sleep(0))
    _frame(loop, synced, model=True)
    assert sent == [(1, True)]


def test_a_page_that_leaves_while_a_frame_is_on_its_way_is_not_kept(
        loop: asyncio.AbstractEventLoop, sent: list[tuple[int, Any]]) -> None:
    """A frame's values are read on the dashboard thread and shown later on the event loop;
    a page that left in between (its disconnect callback run) was written back into the
    per-page values by that frame and stayed there for good: a classroom's browsers come
    and go all day."""
    server, _runtime, synced = _power(loop)
    _frame(loop, synced)
    synced.follow_each(lambda _client_id: True)  # read while page 2 is still there
    gone = server.clients.pop(2)  # viser lets the page go, then runs the callbacks
    synced._gone(gone)  # type: ignore[arg-type]
    complete(loop, asyncio.sleep(0))
    assert 2 not in synced._values and (1, True) in sent
