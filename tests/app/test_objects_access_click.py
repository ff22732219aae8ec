"""The Objects tab's Read / Write: each click does what its page clicked. The button group
has one value for all pages (viser keeps the last click), and a plain callback runs later in
viser's thread pool: page A's Write followed by page B's Read, both callbacks reading the
group's value then, read A's object as if A had clicked Read. The fake viser of
tests/app/fake_viser.py, two pages."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from test_widgets_synced_panels import Server, turn

from app.ui.panels.object_dictionary import ObjectDictionaryPanel


class _Sender:
    def __init__(self) -> None:
        self.sent: list[tuple[str, dict[str, Any]]] = []

    def send(self, client: Any, target: str, action: str, args: dict[str, Any], *,
             done: Callable[[Any], Any] | None = None, confirm: bool = False) -> None:
        self.sent.append((action, args))


def test_two_pages_clicks_each_do_their_own_button() -> None:
    loop = asyncio.new_event_loop()
    try:
        server, sender = Server(loop, pages=2), _Sender()
        panel = ObjectDictionaryPanel(server, None, sender, "cpx")  # type: ignore[arg-type]
        access = server.gui.handles["Access"]
        first, second = server.clients[1], server.clients[2]
        access.user(first, "Write", click=True)
        access.user(second, "Read", click=True)
        turn(loop, server)
        assert sorted(sender.sent, key=lambda s: s[0]) == [
            ("read_object", {"index": 0x5200, "sub": 1}),
            ("write_object", {"index": 0x5200, "sub": 1, "value": 1})]
        assert panel is not None
    finally:
        loop.close()
