"""Per-browser picks: a server-level dropdown whose value is each page's own, and a
server-level HTML element whose content each page gets for its own pick.

viser 1.1.1 sends a server-level widget's change by one browser to every other browser (the
handle's ``sync_cb``) and keeps one value for all, so one trainee's pick of a slave or drive
moved every other page's picker and the panels showing the pick (docs/classroom.md). A pick
here keeps the widget server-level (one uuid, one place in the layout, built once) but stops
that echo and keeps each connection's value itself; what the server sets for one page goes to
that page's connection only. The server's default (a scenario's focus, a test) goes to every
page and is where a new page starts.
"""

from __future__ import annotations

import logging
import threading
import weakref
from collections.abc import Callable, Sequence
from typing import Any

import viser
from viser._messages import GuiUpdateMessage  # viser 1.1.1, pinned

logger = logging.getLogger(__name__)

# The server-side value between picks: no option equals it, so every pick a page sends is a
# change and reaches the callbacks (viser calls them on a change only), whichever page made
# the same pick before.
_NOTHING = "\x00"


_BACKLOG = "_fieldrig_backlog"
_PICKS = "_fieldrig_picks"  # the server's ClientPicks, for resend_overwritten


def page_ready(server: viser.ViserServer, client: viser.ClientHandle) -> bool:
    """True once ``client``'s page has been sent every server-level element that existed when
    it was first asked about. Its own messages and the server's replay of those elements go
    out by two producers in no set order, and the page drops an update of an element it does
    not have yet (viser 1.1.1 client, MessageHandler.tsx): a page's first content sent too
    early was lost for good, its cache saying it was sent (seen: an instructor's page got its
    own messages before the replay)."""
    buffer = server._websock_server._broadcast_buffer
    backlog = getattr(client, _BACKLOG, None)
    if backlog is None:
        backlog = buffer.message_counter - 1
        setattr(client, _BACKLOG, backlog)
    return bool(buffer.generator_cursors.get(client.client_id, -1) >= backlog)


def send_to(client: viser.ClientHandle, uuid: str, prop: str, value: Any) -> None:
    """Set ``prop`` of the widget ``uuid`` on ``client``'s page only."""
    try:
        client.gui._websock_interface.queue_message(GuiUpdateMessage(uuid, {prop: value}))
    except Exception:  # a page that just left
        logger.debug("update for client %s not sent", client.client_id, exc_info=True)


def send_on(client: viser.ClientHandle | None, handle: Any, prop: str, value: Any) -> None:
    """Set ``prop`` of a server-level widget on ``client``'s page, on every page when None."""
    if client is None:
        send_all(handle, prop, value)
    else:
        send_to(client, handle._impl.uuid, prop, value)


def same_head(old: str, new: str) -> bool:
    """Two options naming the same thing: the same first word (a rail slot's number in
    "3 DO16" and "3 (empty)")."""
    return old.split(" ", 1)[0] == new.split(" ", 1)[0]


def send_all(handle: Any, prop: str, value: Any) -> None:
    """Set ``prop`` of a server-level widget on every page, whatever the server last set: a
    page may show another value of its own (viser skips an assignment of the same value)."""
    setattr(handle._impl.props, prop, value)
    handle._queue_update(prop, value)


class ClientPick:
    """A server-level dropdown whose value is each connection's own."""

    def __init__(self, server: viser.ViserServer, handle: Any) -> None:
        self.handle = handle
        self._server = server
        self._lock = threading.Lock()
        self._default = str(handle.value)
        self._own: dict[int, str] = {}
        # Pages whose own pick a broadcast of the default overwrote: the broadcast's message
        # id, after which the page gets its own pick again (set_options, resend).
        self._overwritten: dict[int, int] = {}
        handle._impl.sync_cb = None  # a page's pick goes to no other page
        handle._impl.value = _NOTHING
        handle.on_update(self._picked)
        server.on_client_disconnect(self._gone)
        picks = getattr(server, _PICKS, None)
        if picks is None:
            picks = weakref.WeakSet()
            setattr(server, _PICKS, picks)
        picks.add(self)

    async def _picked(self, event: viser.GuiEvent) -> None:
        # A coroutine: viser awaits it right after storing the page's value, before the next
        # message can overwrite it; the callbacks of on_pick run afterwards in its threads.
        impl = self.handle._impl
        value, impl.value = str(impl.value), _NOTHING
        if value in self.handle.options:
            self._keep(event.client_id, value)

    def _gone(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self._own.pop(client.client_id, None)
            self._overwritten.pop(client.client_id, None)

    def _keep(self, client_id: int, value: str) -> bool:
        """Keep ``value`` as the page's pick, unless the page has left: viser drops it from
        get_clients() before the disconnect callback (_gone), which may have run already; a
        pick kept after it stayed for the server's life (ClientInput.set_for likewise)."""
        if client_id not in self._server.get_clients():
            return False
        with self._lock:
            self._own[client_id] = value
            self._overwritten.pop(client_id, None)  # this value goes to the page last
        if client_id not in self._server.get_clients():  # left meanwhile: _gone may be past
            with self._lock:
                self._own.pop(client_id, None)
            return False
        return True

    def on_pick(self, fn: Callable[[viser.ClientHandle, str], None]) -> None:
        """``fn(client, value)`` after each pick a page makes itself."""
        self.handle.on_update(lambda event: fn(event.client, self.value_for(event.client_id)))

    @property
    def options(self) -> tuple[str, ...]:
        return tuple(self.handle.options)

    @property
    def default(self) -> str:
        """Where a new page starts: the server's last :meth:`set_all`."""
        return self._default

    def value_for(self, client_id: int | None) -> str:
        with self._lock:
            return self._own.get(client_id, self._default) if client_id is not None \
                else self._default

    def set_for(self, client: viser.ClientHandle, value: str) -> None:
        """``client``'s page picks ``value`` (its click in the 3D view)."""
        if self._keep(client.client_id, value):
            send_to(client, self.handle._impl.uuid, "value", value)

    def pick(self, value: str, client: viser.ClientHandle | None) -> bool:
        """``client``'s page picks ``value`` (its click), every page when None (a scenario's
        focus); False when that page already had it (nothing to do)."""
        if client is None:  # every page, also one that picked another on its own
            self.set_all(value)
        elif self.value_for(client.client_id) != value:
            self.set_for(client, value)
        else:
            return False
        return True

    def set_all(self, value: str) -> None:
        """Every page, and every page to come, picks ``value``."""
        with self._lock:
            self._default = value
            self._own.clear()
            self._overwritten.clear()
        self.handle._queue_update("value", value)

    def set_options(self, options: Sequence[str],
                    same: Callable[[str, str], bool] = same_head) -> None:
        """Offer ``options`` on every page. Each page's pick, and a new page's, moves to the
        option naming the same thing (``same(old, new)``), else to the first option. A new
        page's goes to every page (where pages to come start, viser's replay), so a page with
        a pick of its own gets it back once that message has reached it (:meth:`resend`):
        the server's messages to all pages and to one page go out by separate producers in
        no set order (page_ready)."""
        options = tuple(options)
        if not options or options == self.options:
            return

        def moved(value: str) -> str:
            return value if value in options else \
                next((o for o in options if same(value, o)), options[0])

        clients = self._server.get_clients()
        send_all(self.handle, "options", options)
        with self._lock:
            before = self._default
            self._default = moved(before)
            own = {c: moved(v) for c, v in self._own.items() if c in clients}
            changed = {c: v for c, v in own.items() if v != self._own[c]}
            self._own = own
        if self._default != before:
            self.handle._queue_update("value", self._default)
            sent = self._server._websock_server._broadcast_buffer.message_counter - 1
            with self._lock:
                for client_id, value in own.items():
                    if value != self._default:
                        self._overwritten[client_id] = sent
            return
        for client_id, value in changed.items():
            send_to(clients[client_id], self.handle._impl.uuid, "value", value)

    def resend(self) -> None:
        """Each page whose own pick a :meth:`set_options` overwrote gets it again once that
        broadcast has reached it (the dashboard calls it at every tick: resend_overwritten)."""
        if not self._overwritten:
            return
        clients = self._server.get_clients()
        cursors = self._server._websock_server._broadcast_buffer.generator_cursors
        due: list[tuple[viser.ClientHandle, str]] = []
        with self._lock:
            for client_id, sent in list(self._overwritten.items()):
                if client_id not in clients or client_id not in self._own:
                    del self._overwritten[client_id]
                elif cursors.get(client_id, -1) >= sent:
                    del self._overwritten[client_id]
                    due.append((clients[client_id], self._own[client_id]))
        for client, value in due:
            send_to(client, self.handle._impl.uuid, "value", value)


def resend_overwritten(server: viser.ViserServer) -> None:
    """:meth:`ClientPick.resend` of every pick of ``server``: the dashboard calls it at every
    tick, frame or not. Called by the picks' panels only with a new frame, a page whose own
    pick a broadcast reached after the last frame of a paused rig kept the broadcast's (the
    FastCAT Module picker after an Unplug on another page, tests/browser/
    test_picks_two_pages.py)."""
    for pick in list(getattr(server, _PICKS, ())):
        pick.resend()


class ClientHtml:
    """A server-level HTML element whose content each connection gets for itself: what it
    sent last is kept per connection, so a frame sends a page only what changed for it."""

    def __init__(self, server: viser.ViserServer, handle: Any) -> None:
        self._server = server
        self.handle = handle
        self._lock = threading.Lock()  # the dashboard thread and a pick's callback
        self._sent: dict[int, str] = {}

    def show(self, content_for: Callable[[int], str]) -> None:
        """``content_for(client_id)``: that page's content (the dashboard thread)."""
        clients = self._server.get_clients()
        with self._lock:
            for gone in set(self._sent) - set(clients):
                del self._sent[gone]
            for client_id, client in clients.items():
                if not page_ready(self._server, client):
                    continue  # a later frame sends it
                content = content_for(client_id)
                if self._sent.get(client_id) != content:
                    self._sent[client_id] = content
                    send_to(client, self.handle._impl.uuid, "content", content)


class PickedHtml:
    """A server-level HTML element showing each page the content of its pick (``per_page``),
    or one content for all (the pick is everyone's: a rig with one drive)."""

    def __init__(self, server: viser.ViserServer, content: str, per_page: bool) -> None:
        self.handle = server.gui.add_html(content)
        self._pages = ClientHtml(server, self.handle) if per_page else None
        self._last = content

    def show(self, content_of: Callable[[str], str],
             pick_of: Callable[[int | None], str]) -> None:
        """``content_of(pick)``, for each page's ``pick_of(client_id)`` (None: a new page's)."""
        if self._pages is None:
            content = content_of(pick_of(None))
            if content != self._last:
                self.handle.content = self._last = content
            return
        made: dict[str, str] = {}

        def content_for(client_id: int) -> str:
            pick = pick_of(client_id)
            if pick not in made:
                made[pick] = content_of(pick)
            return made[pick]

        self._pages.show(content_for)
