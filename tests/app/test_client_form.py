"""ClientForm (app/ui/panels/client_form.py): a page that has typed nothing holds the box's
initial value, whenever it is asked.

viser 1.1.1 stores a page's value as the widget's (its own message handler, on the event
loop) before the ClientForm's handler, registered after it, puts the initial value back; in
between viser hands the widget's plain callbacks to its thread pool, and the dashboard
thread draws. A read for a page that never typed, in that window, took the widget's value:
the other page's (an Objects Read in the thread pool, a filter or hint in a frame)."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

from fake_viser import Pages
from viser._messages import GuiUpdateMessage

from app.ui.panels.client_form import ClientForm


class _Server:
    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._websock_server = Pages(loop)
        self.clients = {1: SimpleNamespace(client_id=1), 2: SimpleNamespace(client_id=2)}
        self.gone: list[Callable[[Any], None]] = []

    def get_clients(self) -> dict[int, Any]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Callable[[Any], None]) -> None:
        self.gone.append(fn)


def _form() -> tuple[_Server, ClientForm, asyncio.AbstractEventLoop]:
    loop = asyncio.new_event_loop()
    server = _Server(loop)
    handle = SimpleNamespace(_impl=SimpleNamespace(uuid="object", value="0x5200:1", sync_cb=1))
    return server, ClientForm(server, handle), loop  # type: ignore[arg-type]


def test_a_page_that_typed_nothing_reads_the_initial_value_while_viser_holds_another() -> None:
    server, form, loop = _form()
    try:
        form.handle._impl.value = "0x1018:1"  # viser stored page 1's message ...
        assert form.value_for(2) == "0x5200:1"  # ... a read for page 2 meanwhile
        assert form.value_of(None) == "0x5200:1"  # and for no page (a test, a scenario)
        server._websock_server.message(1, GuiUpdateMessage("object", {"value": "0x1018:1"}))
        assert form.value_for(1) == "0x1018:1" and form.value_for(2) == "0x5200:1"
        assert form.handle._impl.value == "0x5200:1"  # what a new page is sent
    finally:
        loop.close()


def test_a_page_that_left_reads_the_initial_value_again() -> None:
    server, form, loop = _form()
    try:
        server._websock_server.message(2, GuiUpdateMessage("object", {"value": "0x6041:0"}))
        client = server.clients.pop(2)
        for fn in server.gone:
            fn(client)
        assert form.value_for(2) == "0x5200:1"
    finally:
        loop.close()
