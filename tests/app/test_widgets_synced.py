"""Synced widgets (app/ui/panels/widgets.py): every page ends up showing the model's value.

The fake viser handle (tests/app/fake_viser.py) behaves as viser 1.1.1 does: a page's change
sets the server's value and runs coroutine callbacks at once on the event loop, plain callbacks
later in a thread pool; assigning ``.value`` sends a message only when the value differs and
calls the callbacks with ``client=None``. The fake runtime applies queued work in arrival order, as
app/runtime.py does. Seed 000 §6.17 (Reset fault: the box is the level of 0x5200:1) is the
example: a refused write (coupler without supply) must put the box back.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator
from types import SimpleNamespace
from typing import Any

import pytest
from fake_viser import Handle, Pages
from own_loop import complete
from viser._messages import GuiUpdateMessage

from app.ui.panels import widgets
from app.ui.panels.widgets import FRESH_AFTER, Synced


class Server:
    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._websock_server = Pages(loop)  # viser 1.1.1's name for it
        self.clients = {c: SimpleNamespace(client_id=c) for c in ("page A", "page B")}

    def get_event_loop(self) -> asyncio.AbstractEventLoop:
        return self._loop

    def get_clients(self) -> dict[str, Any]:
        return dict(self.clients)


@pytest.fixture
def to_page(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, str, Any]]:
    """What goes to one page only: (page, widget id, value)."""
    out: list[tuple[str, str, Any]] = []
    monkeypatch.setattr(widgets, "send_to", lambda client, uuid, prop, value: out.append(
        (client.client_id, uuid, value)))
    return out


class Runtime:
    """The simulation thread: a model value, commands and the sender's work in order."""

    def __init__(self, value: Any, powered: bool = True) -> None:
        self.value = value
        self.powered = powered
        self.work: list[Callable[[], None]] = []
        self.commands: list[Any] = []
        self.refused: list[Any] = []

    def command(self, client: Any, value: Any) -> None:
        def run() -> None:
            if not self.powered:  # CommandError: the coupler is not powered
                self.refused.append(value)
                return
            self.commands.append(value)
            self.value = value
        self.work.append(run)

    def submit(self, client: Any, label: str, fn: Callable[[], Any], *,
               done: Callable[[Any], None] | None = None) -> None:
        def run() -> None:
            result = fn()
            if done is not None:
                done(result)
        self.work.append(run)

    def drain(self) -> None:
        work, self.work = self.work, []
        for fn in work:
            fn()


@pytest.fixture
def loop() -> Iterator[asyncio.AbstractEventLoop]:
    loop = asyncio.new_event_loop()
    yield loop
    loop.close()


def turn(loop: asyncio.AbstractEventLoop, handle: Handle | None = None) -> None:
    """Run what the other threads handed the event loop, then viser's next window."""
    complete(loop, asyncio.sleep(0))
    if handle is not None:
        handle.window()


def rig(loop: asyncio.AbstractEventLoop, value: Any,
        powered: bool = True) -> tuple[Handle, Runtime, Synced]:
    handle = Handle(loop, value)
    runtime = Runtime(value, powered)
    synced = Synced(Server(loop), handle, runtime, runtime.command)  # type: ignore[arg-type]
    synced.follow(runtime.value)
    turn(loop, handle)
    handle.sent.clear()
    return handle, runtime, synced


def frames(loop: asyncio.AbstractEventLoop, synced: Synced, runtime: Runtime,
           n: int = FRESH_AFTER) -> None:
    """``n`` dashboard frames with the model's value."""
    for _ in range(n):
        synced.follow(runtime.value)
        turn(loop, synced.handle)


def test_each_change_commands_the_value_it_set_in_order(loop) -> None:
    """§6.17: the last click wins: commands carry each change's own value, in order."""
    handle, runtime, _synced = rig(loop, False)
    for value in (True, False, True, False, True):
        handle.user("page A", value)
    runtime.drain()
    assert runtime.commands == [True, False, True, False, True]
    assert runtime.value is True


def test_a_plain_callback_would_read_a_later_value(loop) -> None:
    """Why the callbacks are coroutines: a thread-pool callback reads the widget when it runs."""
    handle = Handle(loop, False)
    read: list[bool] = []
    handle.on_update(lambda event: read.append(event.target.value))
    handle.user("page A", True)
    handle.user("page A", False)
    for fn in handle.pool:
        fn()
    assert read == [False, False]  # the True click was never commanded


def test_a_refused_change_puts_the_widget_back(loop) -> None:
    """§6.17 without supply there is no 0x5200:1: the refused click leaves the model False,
    and the box goes back to False on every page."""
    handle, runtime, synced = rig(loop, False, powered=False)
    handle.user("page A", True)
    runtime.drain()
    turn(loop)
    assert runtime.refused == [True] and runtime.value is False
    frames(loop, synced, runtime)
    assert handle.value is False and handle.sent[-1] is False


def test_the_model_value_is_sent_again_when_the_server_already_holds_it(loop) -> None:
    """A page whose click crossed a message can show the opposite of a server copy that equals
    the model; after the command went through, the model's value goes to every page."""
    handle, runtime, synced = rig(loop, False)
    handle.user("page A", True)
    runtime.drain()
    turn(loop)
    assert handle.value is True and runtime.value is True
    before = len(handle.sent)
    frames(loop, synced, runtime)
    assert handle.value is True
    assert len(handle.sent) > before and handle.sent[-1] is True


def test_a_change_stays_shown_until_the_model_took_it(loop) -> None:
    """Frames published before the command ran do not flip the click back."""
    handle, runtime, synced = rig(loop, False)
    handle.user("page A", True)
    frames(loop, synced, runtime, n=3)  # the model is still False: the command is queued
    assert handle.value is True and handle.sent == []
    runtime.drain()
    turn(loop)
    synced.follow(False)  # a frame published before the command ran, read after it
    turn(loop, handle)
    assert handle.sent == []
    frames(loop, synced, runtime)
    assert handle.value is True and handle.sent[-1] is True
    assert False not in handle.sent


def test_the_model_changing_by_itself_is_followed(loop) -> None:
    """No click: a model change (e.g. a power cycle clearing 0x5200:1) reaches the widget."""
    handle, runtime, synced = rig(loop, True)
    runtime.value = False
    frames(loop, synced, runtime, n=1)
    assert handle.value is False and handle.sent == [False]
    frames(loop, synced, runtime, n=3)
    assert handle.sent == [False]  # nothing more while nothing changes


def test_a_burst_from_two_pages_ends_on_the_model(loop) -> None:
    """Two pages at odds, many changes: one re-send after the last has been through."""
    handle, runtime, synced = rig(loop, False)
    for k in range(9):
        handle.user("page A" if k % 2 else "page B", k % 3 == 0)
        if k % 4 == 0:
            runtime.drain()
            turn(loop)
            frames(loop, synced, runtime, n=1)
    runtime.drain()
    turn(loop)
    frames(loop, synced, runtime)
    assert handle.value == runtime.value
    assert handle.sent[-1] == runtime.value


Box = tuple[Handle, Runtime, Synced]


def two_boxes(loop: asyncio.AbstractEventLoop, n: int = 2) -> tuple[Server, list[Box]]:
    """Hold CNF and Reset fault (and ``n`` - 2 more): Synced boxes of one server (one page's
    one sender)."""
    server = Server(loop)
    boxes = []
    for _ in range(n):
        handle = Handle(loop, False)
        runtime = Runtime(False)
        synced = Synced(server, handle, runtime, runtime.command)  # type: ignore[arg-type]
        synced.follow(runtime.value)
        turn(loop, handle)
        handle.sent.clear()
        boxes.append((handle, runtime, synced))
    return server, boxes


def page_message(server: Server, client: str, value: Any) -> None:
    """What viser's websocket server does with any GUI message of a page, after the widget's
    own handler: the other handlers registered for its type."""
    server._websock_server.message(client, GuiUpdateMessage("some-widget", {"value": value}))


def all_frames(loop: asyncio.AbstractEventLoop, boxes: list[Box], n: int = FRESH_AFTER) -> None:
    for _ in range(n):
        for _handle, runtime, synced in boxes:
            synced.follow(runtime.value)
        turn(loop)
        for handle, _runtime, _synced in boxes:
            handle.window()


def test_a_click_the_page_never_sent_goes_back_at_its_next_message(loop, to_page) -> None:
    """viser's page sends every change through one sender throttled to 50 ms, the latest of
    ANY widget (docs/dashboard.md "Fast clicks"): Hold CNF clicked, then Reset fault within
    the window, and the server never hears of the Hold CNF click while the page shows the box
    checked (a CI run of tests/browser/test_ui_abuse.py: the box checked, CNF released). The
    page's next message is the sign: the Hold CNF box sends the model's value to that page."""
    server, boxes = two_boxes(loop)
    (hold, hold_model, _), (reset, reset_model, _) = boxes
    # page A: Hold CNF checked (dropped by the page's sender), Reset fault checked (sent)
    reset.user("page A", True)
    page_message(server, "page A", True)
    reset_model.drain()
    turn(loop)
    all_frames(loop, boxes)
    assert hold_model.value is False and hold_model.commands == []
    assert to_page == [("page A", widgets.widget_uuid(hold), False)]  # back to the model
    assert reset.sent[-1] is True and reset_model.value is True
    all_frames(loop, boxes, n=3)
    assert len(to_page) == 1  # once: nothing more while no page sends anything


def test_a_click_sends_the_watching_pages_only_the_clicked_boxs_value(loop, to_page) -> None:
    """Benchmark 3's clicking case (docs/performance.md): page A clicks Reset fault five
    times among five boxes. Only page A's sender can have dropped a click of page A, so the
    other boxes' values go to page A, once per click each, and to no other page: page B gets
    the clicked box's value after each click (it settled), nothing from the four others."""
    server, boxes = two_boxes(loop, n=5)
    reset, reset_model, _ = boxes[1]
    for value in (True, False, True, False, True):
        reset.user("page A", value)
        page_message(server, "page A", value)
        reset_model.drain()
        turn(loop)
        all_frames(loop, boxes)
    others = [handle for k, (handle, _m, _s) in enumerate(boxes) if k != 1]
    assert [h.sent for h in others] == [[], [], [], []]  # nothing to every page
    assert reset.sent == [True, False, True, False, True]  # the clicked box, settled
    assert {page for page, _uuid, _value in to_page} == {"page A"}
    assert len(to_page) == 4 * 5 and {v for _p, _u, v in to_page} == {False}


def test_a_page_that_left_is_sent_nothing(loop, to_page) -> None:
    server, boxes = two_boxes(loop)
    page_message(server, "page A", True)
    del server.clients["page A"]  # gone before the next frame
    all_frames(loop, boxes)
    assert to_page == [] and [h.sent for h, _m, _s in boxes] == [[], []]


def test_a_pages_message_does_not_undo_a_change_on_its_way(loop) -> None:
    """A box whose own change is queued keeps showing it when a page's message comes in;
    the model's value goes out once the change has been through the runtime."""
    server, boxes = two_boxes(loop)
    (hold, hold_model, _), _reset = boxes
    hold.user("page A", True)
    page_message(server, "page A", True)
    all_frames(loop, boxes, n=3)  # the command is still queued: the model is False
    assert hold.value is True and hold.sent == []
    hold_model.drain()
    turn(loop)
    all_frames(loop, boxes)
    assert hold.value is True and hold.sent[-1] is True and False not in hold.sent


@pytest.mark.parametrize(("value", "other"), [(True, False), (False, True), (3, 4), (2.5, 3.5),
                                              ("OP", "OP ")])
def test_aside_is_another_value_of_the_same_type(value: Any, other: Any) -> None:
    assert widgets._aside(value) == other and type(widgets._aside(value)) is type(value)
