"""ClientPick keeps each page's own pick; a page that left must not be kept. viser drops a page
from get_clients() before it runs the disconnect callbacks, so a pick (a 3D-view click, a
page's dropdown message) handled in between was written back after the callback had removed
the page, and stayed for the server's life: a classroom's browsers come and go all day."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from own_loop import run

from app.ui.panels.client_pick import ClientPick


class _Server:
    def __init__(self) -> None:
        self.clients: dict[int, Any] = {1: SimpleNamespace(client_id=1),
                                        2: SimpleNamespace(client_id=2)}
        self.gone: list[Any] = []

    def get_clients(self) -> dict[int, Any]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Any) -> None:
        self.gone.append(fn)


def _pick() -> tuple[_Server, ClientPick, list[Any]]:
    updates: list[Any] = []
    handle = SimpleNamespace(value="a", options=("a", "b"), on_update=updates.append,
                             _impl=SimpleNamespace(sync_cb=object(), value="a", uuid="u"))
    server = _Server()
    return server, ClientPick(server, handle), updates  # type: ignore[arg-type]


def test_a_click_of_a_page_that_left_is_not_kept() -> None:
    server, pick, _ = _pick()
    client = server.clients.pop(2)  # viser lets the page go, then runs the callbacks
    for fn in server.gone:
        fn(client)
    pick.set_for(client, "b")  # the 3D click's callback, run late
    assert pick.value_for(2) == "a" and 2 not in pick._own


def test_a_dropdown_message_of_a_page_that_left_is_not_kept() -> None:
    server, pick, updates = _pick()
    client = server.clients.pop(2)
    for fn in server.gone:
        fn(client)
    pick.handle._impl.value = "b"  # viser stored the page's message before calling back
    run(updates[0](SimpleNamespace(client_id=2, client=client)))
    assert 2 not in pick._own


def test_a_page_still_there_keeps_its_pick() -> None:
    server, pick, updates = _pick()
    pick.handle._impl.value = "b"
    run(updates[0](SimpleNamespace(client_id=1, client=server.clients[1])))
    assert pick.value_for(1) == "b" and pick.value_for(2) == "a"
