"""A page's own content waits for the server's replay of the elements it updates
(app/ui/panels/client_pick.py ``page_ready``): the page's own messages and the replay go out
by two producers in no set order, and viser's page drops an update of an element it does not
have yet. Sent too early, the Slave or Drive tab's first content was lost for good (its cache
said it was sent); seen as an instructor's page that got its own messages before the
replay."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from app.ui.panels import client_pick
from app.ui.panels.client_pick import ClientHtml


class _Server:
    def __init__(self) -> None:
        self._websock_server = SimpleNamespace(_broadcast_buffer=SimpleNamespace(
            message_counter=40, generator_cursors={}))
        self.clients: dict[int, Any] = {7: SimpleNamespace(client_id=7)}

    def get_clients(self) -> dict[int, Any]:
        return self.clients


def test_a_page_gets_its_content_once_the_replay_reached_it(monkeypatch: Any) -> None:
    sent: list[tuple[int, str]] = []
    monkeypatch.setattr(client_pick, "send_to",
                        lambda client, uuid, prop, value: sent.append((client.client_id, value)))
    server = _Server()
    html = ClientHtml(server, SimpleNamespace(_impl=SimpleNamespace(uuid="u")))  # type: ignore
    buffer = server._websock_server._broadcast_buffer
    html.show(lambda _client_id: "cpx")
    assert sent == []  # the replay has not gone out: the page would drop it
    buffer.message_counter = 55  # newer messages do not move what the page waits for
    buffer.generator_cursors[7] = 38
    html.show(lambda _client_id: "cpx")
    assert sent == []
    buffer.generator_cursors[7] = 39
    html.show(lambda _client_id: "cpx")
    html.show(lambda _client_id: "cpx")
    assert sent == [(7, "cpx")]  # once, when the page has the element
