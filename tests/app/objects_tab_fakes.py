"""Stand-ins for viser and the runtime that the Objects tab (ObjectDictionaryPanel) can be
built on without a browser: handles keep the value they were given, the server's clients are
a dict the test fills, and the runtime answers each dictionary read at once."""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from app.ui.panels.object_dictionary import OdRow


class FakeHandle:
    def __init__(self, value: Any = "") -> None:
        self.value = value
        self.content = ""
        self.options: tuple[str, ...] = ()

    def on_update(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        return fn

    on_click = on_update


class FakeGui:
    def __getattr__(self, name: str) -> Callable[..., FakeHandle]:
        return lambda *args, **kw: FakeHandle(args[1] if len(args) > 1 else "")


class FakeServer:
    def __init__(self) -> None:
        self.gui = FakeGui()
        self.clients: dict[int, object] = {}

    def get_clients(self) -> dict[int, object]:
        return self.clients


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
