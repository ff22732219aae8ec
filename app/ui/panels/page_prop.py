"""A server-level element's property that each page gets for its own pick, as
:class:`app.ui.panels.client_pick.ClientHtml` does for an HTML element's content: a folder's
``visible`` (the FastCAT's encoder section shows on the page that picked an AX2), a
dropdown's ``options`` and ``hint`` (an open rig's Fault box: the codes of the page's own
Table, the description of its own pick).

The server's own value of the property is never set after the element is built: a message to
every page and one to a single page go out by separate producers in no set order, so a later
broadcast could land after a page's own value. Every page gets its own, once it has the
element (``page_ready``). Where the server does broadcast it (a ClientPick's ``options``,
which follow the rig), :meth:`PageProp.overwritten` has every page sent its own value again
once that broadcast has reached it.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import viser

from app.ui.panels.client_pick import page_ready, send_to


class PageProp:
    def __init__(self, server: viser.ViserServer, handle: Any, prop: str) -> None:
        self._server = server
        self._uuid = handle._impl.uuid
        self._prop = prop
        self._lock = threading.Lock()  # the dashboard thread and a pick's callback
        self._sent: dict[int, Any] = {}
        # The last broadcast of the property (a message id): a page gets its own value only
        # once its connection has been sent that message.
        self._after = -1

    def show(self, value_for: Callable[[int], Any]) -> None:
        """``value_for(client_id)``: that page's value; sent when it changed for the page."""
        clients = self._server.get_clients()
        cursors = self._server._websock_server._broadcast_buffer.generator_cursors
        with self._lock:
            after = self._after
            for gone in set(self._sent) - set(clients):
                del self._sent[gone]
            for client_id, client in clients.items():
                if not page_ready(self._server, client) or cursors.get(client_id, -1) < after:
                    continue  # a later frame sends it
                value = value_for(client_id)
                if client_id not in self._sent or self._sent[client_id] != value:
                    self._sent[client_id] = value
                    send_to(client, self._uuid, self._prop, value)

    def overwritten(self) -> None:
        """The property was just sent to every page (the message last queued): each page
        gets its own value again by a later :meth:`show`, once that message has reached it
        (a message to one page and one to all go out by separate producers in no set order,
        so one sent before would be overwritten, as :meth:`ClientPick.resend` tells)."""
        with self._lock:
            self._after = self._server._websock_server._broadcast_buffer.message_counter - 1
            self._sent.clear()

    def sent(self, client_id: int) -> Any:
        """What ``client_id``'s page was sent last (None: nothing yet)."""
        with self._lock:
            return self._sent.get(client_id)
