"""Small pieces the control panels share: input widgets that show device state.

viser keeps one value per server-level widget for every browser, but that value is what the
server last *heard*: a page's change goes to the *other* pages only, and assigning the value
the server already holds sends nothing. So a page whose click crossed a message from the server
(another page's change, the view's own write) keeps showing its click while the server and
the model hold the other value, and no later write of that same value puts it back. Two kinds
of input widget show device state:

- :class:`Synced`, a widget that *is* a device value (Power, Hold CNF, Reset fault, ...). A
  change made in a page becomes one command carrying the value that change set. Once the
  command, or its refusal, has been through the runtime, the widget sends the model's value
  to every page, even when the server's copy already equals it. A page's change may also
  never reach the server: the page sends every GUI message through one sender throttled to
  50 ms that keeps the latest message of *any* widget (viser 1.1.1
  client/src/WebsocketUtils.ts), so a click followed within the window by a click elsewhere
  is dropped while its box stays clicked. The message that replaced it does arrive: on every
  GUI message of a page, each Synced widget sends the model's value again at the next frame,
  to that page only (no other page's sender can have dropped that page's click).
  Whatever the clicks, every page ends up showing the model.
- a form field pre-filled from the device and applied by a separate button (the drive's c7)
  follows the device only when the device's value changes, so what a user types in it is
  not overwritten by the next frame: each page's own, a
  :class:`app.ui.panels.client_input.ClientMirror`.

Writing ``.value`` from the server fires the widget's callbacks with ``event.client is None``;
the callbacks ignore those (:func:`from_user`), so the view never echoes a command back.
"""

from __future__ import annotations

import logging
import threading
import weakref
from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import viser
from viser._messages import (
    GuiButtonHoldMessage,
    GuiFormDirtyMessage,
    GuiFormSubmitMessage,
    GuiUpdateMessage,
)

from app.ui.commands import CommandSender
from app.ui.panels.client_pick import send_to

logger = logging.getLogger(__name__)

# Called with the browser that made a change and the value that change set.
UserChange = Callable[[viser.ClientHandle | None, Any], None]

# Model values a Synced widget lets pass after its commands went through the runtime before it
# sends the model's value: the first can come from a frame published before they ran.
FRESH_AFTER = 2

_NOTHING = object()

# What a page sends through its one throttled sender (viser 1.1.1 client: Generated.tsx,
# Button.tsx, Form.tsx): any of them may have replaced a change the server never heard.
PAGE_SENDS = (GuiUpdateMessage, GuiButtonHoldMessage, GuiFormSubmitMessage, GuiFormDirtyMessage)


def on_button(group: Any, fn: Callable[[viser.GuiEvent, str], None]) -> None:
    """Call ``fn(event, button)`` for each click on a button group, with the button clicked.

    A coroutine, so it runs on viser's event loop as the click arrives, while the group's value
    is still this click's button (a plain callback runs later in a thread pool and can read the
    next click's: Enable, Disable commanded as Disable, Disable). ``fn`` must not block."""
    async def clicked(event: viser.GuiEvent) -> None:
        fn(event, str(event.target.value))

    group.on_click(clicked)


def widget_uuid(handle: Any) -> str:
    """The id viser's client gives a server-level widget in the page. viser 1.1.1 (pinned in
    pyproject.toml) keeps it on the handle's private ``_impl``; the classroom's trainee CSS
    needs it to hide a widget on some pages only."""
    return str(handle._impl.uuid)


SHORT_LABEL_EM = 4.25  # "Fault", "Alarm" and the column's right padding, at any folder depth


def short_label_css(handles: Sequence[Any]) -> str:
    """A style giving these rows' labels a narrower column (:data:`SHORT_LABEL_EM`, viser's
    is 7.25 em less 0.64 em per folder level), so the box gets the room: the Fault and Alarm
    boxes cut the longest "0x0A UNKNOWN_SDO_RD_ANSWER" / "24 ABS_ENCODER_COMMUNICATION" by
    a few characters at 1280x720 (tests/browser/test_picker_text.py). The label box is the
    ``<p>``'s parent (viser 1.1.1 components/common.tsx); its width is an inline style."""
    rules = ", ".join(f'div:has(> p > label[for="{widget_uuid(h)}"])' for h in handles)
    return f"<style>{rules} {{ width: {SHORT_LABEL_EM}em !important; }}</style>"


def instructor_folders(widgets: Sequence[Any]) -> list[Any]:
    """The folders whose every child is one of ``widgets`` or such a folder: hiding the rows of
    ``widgets`` alone leaves their titles on the page, empty. viser 1.1.1 (pinned) keeps a
    folder's children on its private ``_children`` and a widget's folder on
    ``_impl.parent_container_id``."""
    hidden = {widget_uuid(w) for w in widgets}
    candidates: dict[str, Any] = {}
    for widget in widgets:
        impl = widget._impl
        parent = impl.gui_api._container_handle_from_uuid.get(impl.parent_container_id)
        if isinstance(parent, viser.GuiFolderHandle):
            candidates[widget_uuid(parent)] = parent
    found: list[Any] = []
    while candidates:  # a folder hidden may empty its own folder: up until nothing changes
        uuid, folder = candidates.popitem()
        if uuid in hidden or not folder._children or not set(folder._children) <= hidden:
            continue
        hidden.add(uuid)
        found.append(folder)
        impl = folder._impl
        parent = impl.gui_api._container_handle_from_uuid.get(impl.parent_container_id)
        if isinstance(parent, viser.GuiFolderHandle):
            candidates[widget_uuid(parent)] = parent
    return found


def from_user(event: viser.GuiEvent) -> bool:
    """True for a change a person made in a browser, False for the view's own writes."""
    return event.client is not None


def on_user_change(handle: Any, fn: UserChange) -> None:
    """Call ``fn(client, value)`` for every change a person makes to ``handle``, in order.

    The callback is a coroutine, so viser runs it on its event loop right after it applied the
    page's message: the value read there is the one that message set. (A plain callback runs
    later in viser's thread pool and reads whatever the widget holds by then, and two of them
    can queue their commands in either order.)"""
    async def changed(event: viser.GuiEvent) -> None:
        if from_user(event):
            fn(event.client, event.target.value)

    handle.on_update(changed)


def _aside(value: Any) -> Any:
    """Another value of the same type (see :meth:`Synced._resend`)."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, int | float):
        return value + 1
    if isinstance(value, str):
        return value + " "
    raise TypeError(f"cannot re-send a {type(value).__name__} widget value")


class Synced:
    """A widget that commands a device value and shows every page the model's value.

    ``command(client, value)`` queues the device action for a change made in a page (it
    should not block: it runs on viser's event loop). ``follow(value)`` takes the model's
    value from each new frame. While a page's change is on its way to the model the widget
    keeps showing it; afterwards it shows the model's value, including when the command was
    refused or changed nothing."""

    def __init__(self, server: viser.ViserServer, handle: Any, sender: CommandSender,
                 command: UserChange) -> None:
        self.handle = handle
        self._loop = server.get_event_loop()
        self._sender = sender
        self._command = command
        # Event loop only: the widget's value changes there (viser applies the pages' changes
        # there, this class writes it there), so nothing writes between a change and its read.
        self._pending = 0  # changes whose command has not been through the runtime yet
        self._fresh_wait = 0  # model values still to let pass before the re-send
        # Written on the event loop, read by follow(): a change or a re-send is under way.
        self._busy = False
        self._followed: Any = _NOTHING  # follow()'s thread only
        self._server = server
        self._lost: set[int] = set()  # pages that may show a change they never sent: loop only
        on_user_change(handle, self._changed)
        _PageMessages.of(server).add(self)

    def follow(self, value: Any) -> None:
        """The model's value, from any thread (the dashboard's frame update)."""
        if value == self._followed and not self._busy:
            return
        self._followed = value
        self._call(self._show, value)

    # ---- on viser's event loop ---------------------------------------------------------------
    def _changed(self, client: viser.ClientHandle | None, value: Any) -> None:
        self._pending += 1
        self._busy = True
        try:
            self._command(client, value)
        finally:
            # Runtime work runs in arrival order: this no-op runs after the command (or finds
            # it refused), and the frames published after it show what the model made of it.
            self._sender.submit(None, "dashboard view", _nothing,
                                done=lambda _result: self._call(self._settled))

    def _recheck(self, client_id: int) -> None:
        """``client_id``'s page sent a GUI message: a change of this widget it made just
        before may have been dropped by its sender. Send that page the model's value at the
        next frame (the dropped change never reached the model: any frame will do), unless a
        change of this widget is on its way or settling (that ends with a re-send to all)."""
        if self._pending == 0 and self._fresh_wait == 0:
            self._lost.add(client_id)
            self._busy = True

    def _settled(self) -> None:
        self._pending -= 1
        if self._pending == 0:
            self._fresh_wait = FRESH_AFTER

    def _show(self, value: Any) -> None:
        if self._pending:
            return  # the page shows a change the model has not taken yet: leave it
        if self._fresh_wait:
            self._fresh_wait -= 1
            if self._fresh_wait == 0:
                self._resend(value)
                self._lost.clear()  # every page had it
        elif self.handle.value != value:
            self.handle.value = value
            self._lost.clear()
        elif self._lost:
            self._resend_to(self._lost, value)
            self._lost.clear()
        self._busy = self._pending > 0 or self._fresh_wait > 0

    def _resend(self, value: Any) -> None:
        """Send ``value`` to every page, also when the server's copy already holds it (a page
        may show its own click instead). viser sends only a change: step aside and back. Both
        writes happen in this one turn of the event loop, which also runs viser's sending, and
        the second replaces the first in viser's outgoing buffer (one message per widget and
        property): the pages receive the model's value only."""
        if self.handle.value == value:
            self.handle.value = _aside(value)
        self.handle.value = value

    def _resend_to(self, client_ids: set[int], value: Any) -> None:
        """Send ``value`` to these pages only; the server's copy already holds it."""
        clients = self._server.get_clients()
        for client_id in client_ids:
            client = clients.get(client_id)
            if client is not None:  # a page that left is sent nothing
                send_to(client, widget_uuid(self.handle), "value", value)

    def _call(self, fn: Callable[..., None], *args: Any) -> None:
        try:
            self._loop.call_soon_threadsafe(fn, *args)
        except RuntimeError:  # the server stopped: no page left to show anything
            logger.debug("viser's event loop is closed; %s dropped", fn.__name__)


def _nothing() -> None:
    return None


class _PageMessages:
    """The Synced widgets of one server, told of every GUI message a page sends.

    viser 1.1.1 has no public hook for "a page sent something": its websocket server
    (``ViserServer._websock_server``) hands each incoming message to every handler registered
    for its type, in order, on the event loop; the GUI's own handler (registered when the
    server was built) has run the widget's callbacks by the time this one runs."""

    _of: ClassVar[weakref.WeakKeyDictionary[Any, _PageMessages]] = weakref.WeakKeyDictionary()
    _of_lock: ClassVar[threading.Lock] = threading.Lock()

    def __init__(self, server: viser.ViserServer) -> None:
        self._lock = threading.Lock()  # widgets are built in other threads than the loop
        self._synced: weakref.WeakSet[Synced] = weakref.WeakSet()
        for message_cls in PAGE_SENDS:
            server._websock_server.register_handler(message_cls, self._heard)

    @classmethod
    def of(cls, server: viser.ViserServer) -> _PageMessages:
        with cls._of_lock:
            found = cls._of.get(server)
            if found is None:
                found = cls._of[server] = cls(server)
            return found

    def add(self, synced: Synced) -> None:
        with self._lock:
            self._synced.add(synced)

    async def _heard(self, client_id: int, _message: Any) -> None:
        with self._lock:
            widgets = list(self._synced)
        for synced in widgets:
            synced._recheck(client_id)


def set_options(dropdown: Any, options: list[str], keep_prefix: str | None = None) -> None:
    """Replace a dropdown's options, keeping the selection on the entry starting with
    ``keep_prefix`` (e.g. the slot number) when there is one."""
    if list(dropdown.options) == options:
        return
    current = keep_prefix if keep_prefix is not None else str(dropdown.value)
    dropdown.options = tuple(options)
    for option in options:
        if option == current or option.split(" ", 1)[0] == current.split(" ", 1)[0]:
            dropdown.value = option
            return
    if options:
        dropdown.value = options[0]


class DetailHint:
    """A dropdown whose options are short labels ("0x04 MISSING_NODE_ANSWER"), with the long
    text of the picked one ("No answer from the node") as the box's hint. A description glued
    to the label made the box cut it ("0x01 MODULE_CHANGED — A mod"): the box holds about 25
    characters. ``details`` maps a label to its hint; call :meth:`refresh` after replacing
    the options. ``lock``: held while the details and the pick are read and the hint written
    (reentrant): the one the frame update holds while it replaces the details, the options and
    the pick, so a pick's refresh does not write the hint of what it read before."""

    def __init__(self, dropdown: Any, details: Callable[[], dict[str, str]],
                 lock: threading.RLock | None = None) -> None:
        self._dropdown = dropdown
        self._details = details
        self._lock = lock if lock is not None else threading.RLock()
        dropdown.on_update(lambda _event: self.refresh())
        self.refresh()

    def refresh(self) -> None:
        with self._lock:
            hint = self._details().get(str(self._dropdown.value))
            if self._dropdown.hint != hint:
                self._dropdown.hint = hint
