"""The Objects tab reads the dictionary every 2 s only while a browser is connected.

Each read is work for the simulation thread (which then keeps 1 ms naps for a while and moves
the rig's revision): a served rig nobody watches must not pay for it. The first browser to
connect gets a read at the next tick.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from app.ui.panels.object_dictionary import REFRESH_S, ObjectDictionaryPanel


class _Handle:
    def __init__(self, value: Any = "") -> None:
        self.value = value
        self.content = ""

    def on_update(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        return fn

    on_click = on_update


class _Gui:
    def __getattr__(self, name: str) -> Callable[..., _Handle]:
        return lambda *args, **kw: _Handle(args[1] if len(args) > 1 else "")


class _Server:
    def __init__(self) -> None:
        self.gui = _Gui()
        self.clients: dict[int, object] = {}

    def get_clients(self) -> dict[int, object]:
        return self.clients


class _Runtime:
    """Counts the reads; each answered at once with no rows."""

    def __init__(self) -> None:
        self.reads = 0

    def submit(self, fn: Callable[[], Any]) -> Future[Any]:
        self.reads += 1
        done: Future[Any] = Future()
        done.set_result([])
        return done


def test_no_read_without_a_browser_then_one_at_the_first() -> None:
    server, runtime = _Server(), _Runtime()
    panel = ObjectDictionaryPanel(server, runtime, None, "fastcat")  # type: ignore[arg-type]
    for k in range(5):
        panel.tick(now=100.0 + k * REFRESH_S)
    assert runtime.reads == 0
    server.clients[1] = object()
    panel.tick(now=100.0 + 5 * REFRESH_S)
    assert runtime.reads == 1
    panel.tick(now=100.0 + 5.5 * REFRESH_S)
    assert runtime.reads == 1  # every REFRESH_S, not every tick
    panel.tick(now=100.0 + 6 * REFRESH_S)
    assert runtime.reads == 2
