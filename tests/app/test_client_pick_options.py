"""ClientPick.set_options: a picker whose options change with the rig (the FastCAT's Module,
"3 DO16" becoming "3 (empty)" when the module is pulled) keeps each page's own pick on the
option naming the same slot. viser's own options setter sent every page the server's value
when the old one was gone, and a ClientPick's server value is no option at all: every page
would have jumped to the first module. A new page's pick goes to every page, so a page with
a pick of its own gets it again once that broadcast has reached it (the page's own messages
and the broadcast go out by separate producers in no set order)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from app.ui.panels import client_pick
from app.ui.panels.client_pick import ClientPick


class _Server:
    def __init__(self) -> None:
        self._websock_server = SimpleNamespace(_broadcast_buffer=SimpleNamespace(
            message_counter=40, generator_cursors={1: 39, 2: 39}))
        self.clients: dict[int, Any] = {1: SimpleNamespace(client_id=1),
                                        2: SimpleNamespace(client_id=2)}

    def get_clients(self) -> dict[int, Any]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Any) -> None:
        pass


class _Handle:
    def __init__(self, server: _Server) -> None:
        self.options = ("1 DB16", "2 DI16", "3 DO16")
        self.value = "1 DB16"
        self._impl = SimpleNamespace(sync_cb=object(), value="1 DB16", uuid="u",
                                     props=SimpleNamespace(options=self.options))
        self.broadcast: list[tuple[str, Any]] = []
        self._server = server

    def on_update(self, fn: Any) -> None:
        pass

    def _queue_update(self, prop: str, value: Any) -> None:
        if prop == "options":
            self.options = value
        self.broadcast.append((prop, value))
        self._server._websock_server._broadcast_buffer.message_counter += 1


def _setup(monkeypatch: Any) -> tuple[_Server, _Handle, ClientPick, list[tuple[int, Any]]]:
    sent: list[tuple[int, Any]] = []
    monkeypatch.setattr(client_pick, "send_to",
                        lambda client, uuid, prop, value: sent.append((client.client_id, value)))
    server = _Server()
    handle = _Handle(server)
    return server, handle, ClientPick(server, handle), sent  # type: ignore[arg-type]


def test_a_page_s_pick_follows_its_slot_s_new_label(monkeypatch: Any) -> None:
    server, handle, pick, sent = _setup(monkeypatch)
    pick.set_for(server.clients[1], "3 DO16")
    sent.clear()
    pick.set_options(("1 DB16", "2 DI16", "3 (empty)"))
    assert handle.broadcast == [("options", ("1 DB16", "2 DI16", "3 (empty)"))]
    assert sent == [(1, "3 (empty)")]  # the default did not move: nothing broadcast
    assert pick.value_for(1) == "3 (empty)" and pick.value_for(2) == "1 DB16"


def test_a_page_s_own_pick_comes_back_after_the_new_default(monkeypatch: Any) -> None:
    server, handle, pick, sent = _setup(monkeypatch)
    pick.set_for(server.clients[1], "3 DO16")
    sent.clear()
    pick.set_options(("1 (empty)", "2 DI16", "3 DO16"))
    assert handle.broadcast[-1] == ("value", "1 (empty)")  # where new pages start
    assert pick.default == "1 (empty)" and pick.value_for(2) == "1 (empty)"
    pick.resend()
    assert sent == []  # the broadcast has not reached page 1: it would overwrite this
    server._websock_server._broadcast_buffer.generator_cursors[1] = 41
    pick.resend()
    pick.resend()
    assert sent == [(1, "3 DO16")]  # once, after it
    assert pick.value_for(1) == "3 DO16"


def test_a_vanished_option_falls_back_to_the_first(monkeypatch: Any) -> None:
    server, _handle, pick, _sent = _setup(monkeypatch)
    pick.set_for(server.clients[2], "3 DO16")
    pick.set_options(("1 DB16", "2 DI16"))
    assert pick.value_for(2) == "1 DB16"


def test_a_pick_made_meanwhile_is_not_overwritten(monkeypatch: Any) -> None:
    server, _handle, pick, sent = _setup(monkeypatch)
    pick.set_for(server.clients[1], "3 DO16")
    pick.set_options(("1 (empty)", "2 DI16", "3 DO16"))
    pick.set_for(server.clients[1], "2 DI16")  # the page's click after the broadcast
    sent.clear()
    server._websock_server._broadcast_buffer.generator_cursors[1] = 41
    pick.resend()
    assert sent == [] and pick.value_for(1) == "2 DI16"


def test_every_pick_of_a_server_resends_at_a_tick_without_a_frame(monkeypatch: Any) -> None:
    """On a paused rig no frame may come after the broadcast reached the page: the
    dashboard's every tick resends (resend_overwritten), not only a panel's update."""
    server, _handle, pick, sent = _setup(monkeypatch)
    other = ClientPick(server, _Handle(server))  # type: ignore[arg-type]
    pick.set_for(server.clients[1], "3 DO16")
    other.set_for(server.clients[2], "2 DI16")
    sent.clear()
    pick.set_options(("1 (empty)", "2 DI16", "3 DO16"))
    client_pick.resend_overwritten(server)  # type: ignore[arg-type]
    assert sent == []
    server._websock_server._broadcast_buffer.generator_cursors[1] = 41
    client_pick.resend_overwritten(server)  # type: ignore[arg-type]
    assert sent == [(1, "3 DO16")]
