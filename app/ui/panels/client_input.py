"""Server-level inputs whose value each page has for itself: the drive controls of a rig with
several drives, where each page commands and shows the drive it picked (the Servo drive
picker, app/ui/panels/client_pick.py).

viser 1.1.1 calls a widget's callbacks only when a page's value differs from the one the
server kept, which is any page's last; here every page's change is read off its message
(a handler of the server's websocket, run after viser's own), so page B's click that
equals page A's is not lost. A page's change goes to no other page (``sync_cb``).
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable
from typing import Any

import viser
from viser._messages import GuiUpdateMessage  # viser 1.1.1, pinned

from app.ui.commands import CommandSender
from app.ui.panels.client_pick import page_ready, send_to
from app.ui.panels.widgets import PAGE_SENDS

logger = logging.getLogger(__name__)

ClientChange = Callable[[viser.ClientHandle | None, Any], None]


class ClientInput:
    """A server-level input whose value is each connection's own (a form field)."""

    def __init__(self, server: viser.ViserServer, handle: Any) -> None:
        self._server = server
        self.handle = handle
        self._lock = threading.Lock()
        self._values: dict[int, Any] = {}
        handle._impl.sync_cb = None
        server._websock_server.register_handler(GuiUpdateMessage, self._message)
        server.on_client_disconnect(self._gone)

    def _message(self, client_id: int, message: GuiUpdateMessage) -> None:
        """viser's event loop, after viser applied the message."""
        if message.uuid != self.handle._impl.uuid or "value" not in message.updates:
            return
        impl = self.handle._impl
        value = message.updates["value"]
        if not isinstance(impl.value, tuple):  # as viser casts it (a number box sends ints)
            value = type(impl.value)(value)
        with self._lock:
            self._values[client_id] = value
        self.changed(client_id, value)

    def changed(self, client_id: int, value: Any) -> None:
        """A page's change (viser's event loop): for subclasses."""

    def _gone(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self._values.pop(client.client_id, None)

    def value_for(self, client_id: int | None) -> Any:
        """What ``client_id``'s page shows (the server's value when it is not known)."""
        with self._lock:
            return self._values.get(client_id, self.handle._impl.value) \
                if client_id is not None else self.handle._impl.value

    def set_for(self, client: viser.ClientHandle, value: Any) -> None:
        with self._lock:
            self._values[client.client_id] = value
        if client.client_id not in self._server.get_clients():
            # A frame read before the page left: viser drops it from get_clients() before
            # the disconnect callback (_gone), which may have run already; kept, it stayed.
            with self._lock:
                self._values.pop(client.client_id, None)
            return
        send_to(client, self.handle._impl.uuid, "value", value)



class ClientMirror(ClientInput):
    """A form field filled from the model (app/ui/panels/widgets.py) per page: from the model of
    each page's pick, when that value changes for the page (its drive's changed, or it
    picked another drive); what the page types stays until then."""

    def __init__(self, server: viser.ViserServer, handle: Any) -> None:
        super().__init__(server, handle)
        self._seen: dict[int | None, Any] = {}
        self._seen_lock = threading.Lock()  # the dashboard thread and a pick's callback
        self._initial = handle._impl.value

    def _new_page(self) -> Any:
        """A new page's value: the model's, the last :meth:`follow_each` took for None."""
        with self._seen_lock:
            return self._seen.get(None, self._initial)

    def changed(self, client_id: int, value: Any) -> None:
        # viser kept the page's value as the widget's, which a new page is sent
        self.handle._impl.value = self._new_page()

    def value_for(self, client_id: int | None) -> Any:
        """What ``client_id``'s page holds (the model's value for a page not filled yet);
        never viser's value, which a page's message sets before :meth:`changed` puts the
        model's back (app/ui/panels/client_form.py likewise)."""
        with self._lock:
            if client_id in self._values:
                return self._values[client_id]
        return self._new_page()

    def follow_each(self, value_for: Callable[[int | None], Any]) -> None:
        """``value_for(client_id)``; None: a new page's, kept as the server's value without
        sending it (the pages get theirs), which is what reading ``handle.value`` gives."""
        clients = self._server.get_clients()
        with self._seen_lock:
            value = value_for(None)
            if value is not None and value != self._seen.get(None, _NOTHING):
                self._seen[None] = self.handle._impl.value = value
            for gone in set(self._seen) - set(clients) - {None}:
                del self._seen[gone]
            for client_id, client in clients.items():
                if not page_ready(self._server, client):
                    continue  # a later frame sends it
                value = value_for(client_id)
                if value is not None and value != self._seen.get(client_id, _NOTHING):
                    self._seen[client_id] = value
                    self.set_for(client, value)

    def forget(self, client_id: int | None = None) -> None:
        """Take the next value even if it equals the last one: ``client_id``'s page picked
        another drive (every page's when None)."""
        with self._seen_lock:
            if client_id is None:
                self._seen.clear()
            else:
                self._seen.pop(client_id, None)


class ClientSynced(ClientInput):
    """:class:`app.ui.panels.widgets.Synced` per page: each page shows the model's value of
    its own pick (``follow_each``), a page's change commands ``command(client, value)`` and
    stays shown on that page until the command has been through the runtime, then the
    model's value goes back to it (a refused or no-op command included). As with Synced, any
    GUI message of a page may have replaced a change of this widget its throttled sender
    dropped: that page gets the model's value again at the next frame."""

    def __init__(self, server: viser.ViserServer, handle: Any, sender: CommandSender,
                 command: ClientChange) -> None:
        super().__init__(server, handle)
        self._loop: asyncio.AbstractEventLoop = server.get_event_loop()
        self._sender = sender
        self._command = command
        self._pending: dict[int, int] = {}  # event loop only
        self._model: dict[int, Any] = {}  # what each page was last told: event loop only
        for message_cls in PAGE_SENDS:
            server._websock_server.register_handler(message_cls, self._heard)

    def _heard(self, client_id: int, _message: Any) -> None:
        """viser's event loop: ``client_id``'s page may show a click the server never heard
        (widgets.Synced._recheck); a change of its own on its way is left to settle."""
        self._model.pop(client_id, None)

    def changed(self, client_id: int, value: Any) -> None:
        self._pending[client_id] = self._pending.get(client_id, 0) + 1
        self._model.pop(client_id, None)  # the page shows its click: the model's goes again
        try:
            self._command(self._server.get_clients().get(client_id), value)
        finally:
            self._sender.submit(None, "dashboard view", _nothing,
                                done=lambda _r: self._call(self._settled, client_id))

    def _settled(self, client_id: int) -> None:
        self._pending[client_id] -= 1
        if not self._pending[client_id]:
            del self._pending[client_id]

    def follow_each(self, value_for: Callable[[int], Any]) -> None:
        """The model's value for each page (the dashboard thread, each frame)."""
        clients = self._server.get_clients()
        values = {c: value_for(c) for c in clients}
        self._call(self._show, values, clients)

    def _show(self, values: dict[int, Any], clients: dict[int, viser.ClientHandle]) -> None:
        for gone in set(self._model) - set(clients):
            del self._model[gone]
        for client_id, value in values.items():
            if value is None or self._pending.get(client_id) \
                    or not page_ready(self._server, clients[client_id]):
                continue  # a later frame sends it
            if self._model.get(client_id, _NOTHING) != value:
                self._model[client_id] = value
                self.set_for(clients[client_id], value)

    def _call(self, fn: Callable[..., None], *args: Any) -> None:
        try:
            self._loop.call_soon_threadsafe(fn, *args)
        except RuntimeError:  # the server stopped: no page left to show anything
            logger.debug("viser's event loop is closed; %s dropped", fn.__name__)


_NOTHING = object()


def _nothing() -> None:
    return None
