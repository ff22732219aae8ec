"""A fake of what viser 1.1.1 does for the widgets that mirror a device (docs/stack-notes.md).

A page's change sets the server's value and runs coroutine callbacks at once on the event
loop, plain callbacks later in a thread pool (``pool``: run them when the test says);
assigning ``.value`` sends a message only when the value differs and calls the callbacks with
``client=None``; the messages of one turn of the event loop for one widget coalesce (viser's
outgoing buffer keeps the last update per widget and property until its next window).
A page's GUI messages all pass viser's websocket server, which hands each to every handler
registered for its type, in order, on the event loop (:class:`Pages`: ``message()``); a
handle given ``pages`` hands them a page's change after its own callbacks, as viser's
handler runs first. A :class:`FakePage` keeps what the server sent that page alone
(``client_pick.send_to``) and its notices.
Shared by tests/app/test_widgets_synced.py and test_widgets_synced_panels.py.
"""

from __future__ import annotations

import asyncio
import inspect
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from own_loop import complete
from viser._messages import GuiUpdateMessage


class Pages:
    """viser's websocket server (``ViserServer._websock_server``) as far as handlers go."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self.handlers: dict[type, list[Callable[[Any, Any], Any]]] = {}

    def register_handler(self, message_cls: type, callback: Callable[[Any, Any], Any]) -> None:
        self.handlers.setdefault(message_cls, []).append(callback)

    def message(self, client_id: Any, message: Any) -> None:
        """A page's message reaches the server: every handler of its type, in order."""
        for fn in list(self.handlers.get(type(message), [])):
            out = fn(client_id, message)
            if inspect.iscoroutine(out):
                complete(self._loop, out)


@dataclass
class Event:
    client: Any
    target: Any

    @property
    def client_id(self) -> Any:
        return getattr(self.client, "client_id", self.client)


class FakePage:
    """A connected page (viser's ClientHandle as far as the panels go)."""

    def __init__(self, client_id: int) -> None:
        self.client_id = client_id
        self.gui = self  # send_to: client.gui._websock_interface.queue_message
        self._websock_interface = self
        self.messages: list[GuiUpdateMessage] = []
        self.notices: list[tuple[str, str]] = []

    def queue_message(self, message: GuiUpdateMessage) -> None:
        self.messages.append(message)

    def add_notification(self, title: str, body: str, **_: Any) -> None:
        self.notices.append((title, body))

    def sent(self, uuid: str, prop: str) -> list[Any]:
        """What the server set on this page alone, for ``prop`` of widget ``uuid``."""
        return [m.updates[prop] for m in self.messages
                if m.uuid == uuid and prop in m.updates]


class _Impl:
    """The handle's ``_impl`` (viser 1.1.1): the value without sending it, the uuid, the
    echo to the other pages."""

    _uuids = itertools.count()

    def __init__(self, handle: Handle) -> None:
        self._handle = handle
        self.uuid = f"{handle.label or 'widget'}-{next(self._uuids)}"
        self.sync_cb: Any = object()

    @property
    def value(self) -> Any:
        return self._handle._value

    @value.setter
    def value(self, value: Any) -> None:
        self._handle._value = value


class Handle:
    """Any server-level viser GUI handle; ``sent`` holds the values sent to every page (what
    goes to one page only is app.ui.panels.client_pick.send_to's: tests record that)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, value: Any, label: str = "",
                 options: tuple[str, ...] = (), pool: list[Callable[[], Any]] | None = None,
                 pages: Pages | None = None) -> None:
        self._loop = loop
        self._pages = pages
        self.pool = pool if pool is not None else []  # plain callbacks not run yet
        self.label = label
        self._value = value
        self.options = options
        self.callbacks: list[Callable[[Event], Any]] = []
        self.sent: list[Any] = []
        self.outbox: list[Any] = []  # this turn's messages; the last one goes out
        self.visible = True
        self.disabled = False
        self.content = ""
        self.hint: str | None = None
        self._impl = _Impl(self)

    def __enter__(self) -> Handle:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def on_update(self, fn: Callable[[Event], Any]) -> None:
        self.callbacks.append(fn)

    on_click = on_update

    @property
    def value(self) -> Any:
        return self._value

    @value.setter
    def value(self, value: Any) -> None:
        if value == self._value:
            return  # viser: an unchanged value sends nothing
        self.outbox.append(value)
        self._value = value
        for fn in self.callbacks:
            out = fn(Event(None, self))
            if inspect.iscoroutine(out):
                self._loop.create_task(out)

    def window(self) -> None:
        """viser sends its next window."""
        if self.outbox:
            self.sent.append(self.outbox[-1])
            self.outbox.clear()

    def user(self, client: str, value: Any, click: bool = False) -> None:
        """A page's change (or a button group's click, which always counts), as viser's
        message handler applies it: coroutine callbacks at once, plain ones later in a pool."""
        if value == self._value and not click:
            self._handed(client, value)
            return
        self._value = value
        for fn in self.callbacks:
            if inspect.iscoroutinefunction(fn):
                complete(self._loop, fn(Event(client, self)))
            else:
                self.pool.append(lambda fn=fn, client=client: fn(Event(client, self)))
        self._handed(client, value)

    def _handed(self, client: Any, value: Any) -> None:
        """The other handlers of the page's message, after viser's."""
        if self._pages is not None:
            self._pages.message(Event(client, self).client_id,
                                GuiUpdateMessage(self._impl.uuid, {"value": value}))
