"""Stand-ins for viser and the runtime that the Objects tab (ObjectDictionaryPanel) can be
built on without a browser: handles keep the value they were given, the server's clients are
a dict the test fills (fake_viser.FakePage: what the server sent each page alone), each
already sent the shared elements (client_pick.page_ready), a page's message goes to the
handlers registered on the websocket server (``message``), and the runtime answers each
dictionary read at once."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from concurrent.futures import Future
from types import SimpleNamespace
from typing import Any

from fake_viser import FakePage
from viser._messages import GuiUpdateMessage

from app.ui.panels.object_dictionary import OdRow

_UUIDS = itertools.count()


class FakeHandle:
    def __init__(self, value: Any = "") -> None:
        # viser 1.1.1's _impl holds the value; ``value`` is the same, as on a viser handle
        self._impl = SimpleNamespace(value=value, uuid=f"widget-{next(_UUIDS)}", sync_cb=1)
        self.content = ""
        self.options: tuple[str, ...] = ()

    @property
    def value(self) -> Any:
        return self._impl.value

    @value.setter
    def value(self, value: Any) -> None:
        self._impl.value = value

    def on_update(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        return fn

    on_click = on_update


class FakeGui:
    def __getattr__(self, name: str) -> Callable[..., FakeHandle]:
        return lambda *args, **kw: FakeHandle(args[1] if len(args) > 1 else "")


class _Websocket:
    def __init__(self, server: FakeServer) -> None:
        self._server = server
        self.handlers: list[Callable[[int, Any], Any]] = []
        self._broadcast_buffer = SimpleNamespace(message_counter=1, generator_cursors=self)

    def register_handler(self, message_cls: type, fn: Callable[[int, Any], Any]) -> None:
        if message_cls is GuiUpdateMessage:
            self.handlers.append(fn)

    def get(self, client_id: int, default: int) -> int:
        """Every page's cursor is past the replay."""
        return 5 if client_id in self._server.clients else default


class FakeServer:
    def __init__(self) -> None:
        self.gui = FakeGui()
        self.clients: dict[int, FakePage] = {}
        self._websock_server = _Websocket(self)

    def get_clients(self) -> dict[int, FakePage]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Callable[[Any], None]) -> None:
        return None

    def connect(self, client_id: int) -> FakePage:
        self.clients[client_id] = page = FakePage(client_id)
        return page

    def message(self, client_id: int, handle: FakeHandle, value: Any) -> None:
        """A page's change of ``handle``, as viser stores it, then the other handlers."""
        handle._impl.value = value
        for fn in list(self._websock_server.handlers):
            fn(client_id, GuiUpdateMessage(handle._impl.uuid, {"value": value}))


class FakeRuntime:
    """Counts the dictionary reads; each answered at once with ``rows``, the dictionary of
    ``device`` (the one the panel shows)."""

    def __init__(self, rows: list[OdRow] | None = None, device: str = "fastcat") -> None:
        self.rows = rows or []
        self.device = device
        self.reads = 0

    def submit(self, fn: Callable[[], Any]) -> Future[Any]:
        self.reads += 1
        done: Future[Any] = Future()
        done.set_result({self.device: self.rows})
        return done
