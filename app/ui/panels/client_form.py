"""Form fields each page fills for itself (a register number, an object's address, a filter).
A widget property each page gets for its own content (a box's hint) is a
:class:`app.ui.panels.page_prop.PageProp`.

A :class:`~app.ui.panels.client_input.ClientInput` keeps each page's value, but a page that
has typed nothing read viser's value, which is the last value any page sent: page B's Read
took the register page A had picked. A :class:`ClientForm` gives such a page the field's
initial value, as its browser shows it, and puts that value back as viser's after each
page's change, which is what a new page is sent (docs/dashboard.md "Several browsers").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import viser

from app.ui.panels.client_input import ClientInput

FormChange = Callable[[viser.ClientHandle, Any], None]


class ClientForm(ClientInput):
    """A server-level form field whose value is each page's own; ``on_change(client,
    value)``: after each change a page makes (viser's event loop: it must not block)."""

    def __init__(self, server: viser.ViserServer, handle: Any,
                 on_change: FormChange | None = None) -> None:
        super().__init__(server, handle)
        self.initial = handle._impl.value
        self._on_change = on_change

    def changed(self, client_id: int, value: Any) -> None:
        # viser kept the page's value as the widget's: every other page would read it
        self.handle._impl.value = self.initial
        client = self._server.get_clients().get(client_id)
        if self._on_change is not None and client is not None:
            self._on_change(client, value)

    def value_for(self, client_id: int | None) -> Any:
        """What ``client_id``'s page holds, the initial value for a page that has typed
        nothing. Never viser's value: viser stores a page's value as the widget's before
        :meth:`changed` puts the initial one back, and a read in between (viser's thread
        pool, the dashboard thread) took the other page's for this one."""
        with self._lock:
            return self._values.get(client_id, self.initial) if client_id is not None \
                else self.initial

    def value_of(self, client: Any) -> Any:
        """What ``client``'s page holds (the initial value for no page: a test, a scenario)."""
        return self.value_for(getattr(client, "client_id", None))

