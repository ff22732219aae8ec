"""The drive and master panels' device-value widgets are Synced (issue 7, the checkbox
mirror bug): a change commands the value it set, to the device selected when it reached the
server; a refused or lost change goes back to the model's value on every page; a selection
change shows the newly selected device's value.

The fake GUI behaves as viser 1.1.1 does for what Synced relies on (docs/stack-notes.md, and
tests/app/test_widgets_synced.py for the widget alone): a page's change sets the server's value
and runs coroutine callbacks on the event loop; assigning ``.value`` sends a message only when
the value differs, and the last message of one turn of the loop is the one that goes out.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator
from types import SimpleNamespace
from typing import Any

import pytest
from fake_viser import FakePage, Handle, Pages
from own_loop import complete

from app.classroom.roles import Role
from app.ui.drive.drive_options import mode_option
from app.ui.drive.drive_panel import DrivePanel
from app.ui.line.master_panel import LOG_STYLES, MasterPanel
from app.ui.panels.widgets import FRESH_AFTER


class Gui:
    def __init__(self, loop: asyncio.AbstractEventLoop, pages: Pages | None = None) -> None:
        self._loop = loop
        self._pages = pages
        self.handles: dict[str, Handle] = {}
        self.pool: list[Callable[[], Any]] = []  # viser's thread pool: plain callbacks

    def _add(self, label: str, value: Any, options: tuple[str, ...] = ()) -> Handle:
        handle = Handle(self._loop, value, label, options, self.pool, self._pages)
        self.handles.setdefault(label, handle)
        return handle

    def add_checkbox(self, label: str, initial_value: bool, **_: Any) -> Handle:
        return self._add(label, initial_value)

    def add_dropdown(self, label: str, options: Any, initial_value: Any = None,
                     **_: Any) -> Handle:
        options = tuple(options)
        return self._add(label, options[0] if initial_value is None else initial_value, options)

    def add_button_group(self, label: str, options: Any, **_: Any) -> Handle:
        return self._add(label, next(iter(options)), tuple(options))

    def add_number(self, label: str, initial_value: Any, **_: Any) -> Handle:
        return self._add(label, initial_value)

    def add_text(self, label: str, initial_value: str, **_: Any) -> Handle:
        return self._add(label, initial_value)

    def add_button(self, label: str, hint: str | None = None, **_: Any) -> Handle:
        handle = self._add(label, False)
        handle.hint = hint
        return handle

    def add_folder(self, label: str, **_: Any) -> Handle:
        return self._add(f"folder {label}", None)

    def add_html(self, content: str, **_: Any) -> Handle:
        handle = Handle(self._loop, None, "html", pages=self._pages)
        handle.content = content
        return handle

    def add_progress_bar(self, value: float, **_: Any) -> Handle:
        return self._add("progress", value)

    def windows(self) -> None:
        for handle in self.handles.values():
            handle.window()


class Server:
    """viser's server with ``pages`` connected (FakePage), each already sent the replay of
    the shared elements (client_pick.page_ready)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, pages: int = 0) -> None:
        self._loop = loop
        self._websock_server = Pages(loop)  # viser 1.1.1's name for it
        self.gui = Gui(loop, self._websock_server)
        self.clients = {k: FakePage(k) for k in range(1, pages + 1)}
        self._websock_server._broadcast_buffer = SimpleNamespace(  # type: ignore[attr-defined]
            message_counter=1, generator_cursors=dict.fromkeys(self.clients, 5))

    def get_event_loop(self) -> asyncio.AbstractEventLoop:
        return self._loop

    def get_clients(self) -> dict[int, FakePage]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Callable[[Any], None]) -> None:
        return None


class Sender:
    """The runtime's queue: commands and submitted work run in arrival order on drain()."""

    def __init__(self) -> None:
        self.work: list[Callable[[], None]] = []
        self.sent: list[tuple[str, str, dict[str, Any]]] = []
        self.labels: list[str] = []

    def send(self, client: Any, target: str, action: str, args: dict[str, Any] | None = None,
             *, done: Callable[[Any], None] | None = None, confirm: bool = False) -> None:
        self.work.append(lambda: self.sent.append((target, action, dict(args or {}))))

    def submit(self, client: Any, label: str, fn: Callable[[], Any], *,
               done: Callable[[Any], None] | None = None) -> None:
        def run() -> None:
            if label != "dashboard view":
                self.labels.append(label)
                return  # the panels' own work needs a rig: what it was asked is enough here
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


def turn(loop: asyncio.AbstractEventLoop, server: Server) -> None:
    """The pool's callbacks, what the other threads handed the event loop, viser's window."""
    pool, server.gui.pool[:] = list(server.gui.pool), []
    for fn in pool:
        fn()
    complete(loop, asyncio.sleep(0))
    server.gui.windows()


def frames(loop: asyncio.AbstractEventLoop, server: Server, update: Callable[[], None],
           n: int = FRESH_AFTER + 1) -> None:
    for _ in range(n):
        update()
        turn(loop, server)


# ---- the servo drive (seed 004) --------------------------------------------------------------
DRIVE = {"powered": True, "ten": True, "ien": True, "jammed": False, "mode": 1,
         "fieldbus": "modbus", "node_id": 1}

# (label, snapshot key, clicked value, command it must send, snapshot value shown back)
DRIVE_WIDGETS = [
    ("Drive power", "powered", False, ("power", {"on": False}), False),
    ("TEN (24 V)", "ten", False, ("set_input", {"name": "ten", "value": False}), False),
    ("IEN (24 V)", "ien", False, ("set_input", {"name": "ien", "value": False}), False),
    ("Load jammed", "jammed", True, ("jam_load", {"active": True}), True),
    ("Mode", "mode", mode_option(3), ("set_mode", {"mode": 3}), 3),
]


def drive_rig(loop: asyncio.AbstractEventLoop) -> tuple[Server, Sender, DrivePanel, list[str]]:
    server, sender, selected = Server(loop), Sender(), ["drive1"]
    panel = DrivePanel(server, None, sender, lambda _client: selected[0], {})  # type: ignore[arg-type]
    frames(loop, server, lambda: panel.update(DRIVE))
    return server, sender, panel, selected


@pytest.mark.parametrize(("label", "key", "clicked", "command", "model"), DRIVE_WIDGETS)
def test_a_drive_change_commands_its_value_and_a_refused_one_goes_back(
        loop, label: str, key: str, clicked: Any, command: tuple[str, dict[str, Any]],
        model: Any) -> None:
    """Seed 004 ch. 2 (power, TEN / IEN inputs), the modes of R35: the command carries the
    change's value to the selected drive; a model that did not take it puts the widget back."""
    server, sender, panel, _ = drive_rig(loop)
    handle = server.gui.handles[label]
    before = handle.value
    handle.user("page A", clicked)
    sender.drain()
    assert sender.sent == [("drive1", *command)]
    turn(loop, server)
    frames(loop, server, lambda: panel.update(DRIVE))  # the drive kept its value
    assert handle.value == before and handle.sent[-1] == before
    handle.sent.clear()
    frames(loop, server, lambda: panel.update({**DRIVE, key: model}))  # it changed by itself
    assert handle.value == clicked and handle.sent == [clicked]


def test_a_drive_change_in_the_page_is_resent_when_the_server_holds_the_model(loop) -> None:
    """The crossing: the server's copy already equals what the drive ends with; the value goes
    to every page anyway, so a page still showing its own click is put right."""
    server, sender, panel, _ = drive_rig(loop)
    handle = server.gui.handles["Drive power"]
    handle.user("page A", False)
    sender.drain()
    turn(loop, server)
    frames(loop, server, lambda: panel.update({**DRIVE, "powered": False}))
    assert handle.value is False and handle.sent[-1] is False


@pytest.mark.parametrize(("label", "key", "clicked", "command", "model"), DRIVE_WIDGETS)
def test_another_drive_selected_shows_its_values(
        loop, label: str, key: str, clicked: Any, command: tuple[str, dict[str, Any]],
        model: Any) -> None:
    """A selection change: the widgets show the new drive's values; a click goes to it."""
    server, sender, panel, selected = drive_rig(loop)
    handle = server.gui.handles[label]
    selected[0] = "drive2"
    panel.forget()
    frames(loop, server, lambda: panel.update({**DRIVE, key: model}))
    assert handle.value == clicked
    handle.user("page A", _other(handle, clicked))
    sender.drain()
    assert sender.sent and sender.sent[0][0] == "drive2"


def _other(handle: Handle, value: Any) -> Any:
    if isinstance(value, bool):
        return not value
    return next(o for o in handle.options if o != value)


def test_c9_and_c7_stay_forms(loop) -> None:
    """c9 and c7 are applied by their button: a frame does not overwrite what a user typed,
    and what one page typed is its own (the other page and a new one keep the drive's)."""
    server, sender = Server(loop, pages=2), Sender()
    panel = DrivePanel(server, None, sender, lambda _client: "drive1", {})  # type: ignore[arg-type]
    frames(loop, server, lambda: panel.update(DRIVE))
    c7, page, other = server.gui.handles["Node (c7)"], server.clients[1], server.clients[2]
    assert page.sent(c7._impl.uuid, "value") == other.sent(c7._impl.uuid, "value") == [1]
    c7.user(page, 42)
    frames(loop, server, lambda: panel.update(DRIVE))
    mirror = panel._mirrors["c7"]
    assert (mirror.value_for(1), mirror.value_for(2), c7.value) == (42, 1, 1)
    assert page.sent(c7._impl.uuid, "value") == [1]  # the frames left what it typed


@pytest.mark.parametrize(("label", "clicks", "commands"), [
    ("Torque", ("Enable", "Disable", "Enable"),
     [("enable", {"on": True}), ("enable", {"on": False}), ("enable", {"on": True})]),
    ("Jog", ("Jog +", "Jog 0", "Jog -"),
     [("jog", {"direction": 1}), ("jog", {"direction": 0}), ("jog", {"direction": -1})]),
])
def test_a_burst_on_a_button_group_commands_each_clicks_button_in_order(
        loop, label: str, clicks: tuple[str, ...], commands: list[Any]) -> None:
    """Issue 7: each click commands its own button, in order (not the group's later value)."""
    server, sender, _panel, _ = drive_rig(loop)
    for button in clicks:
        server.gui.handles[label].user("page A", button, click=True)
    turn(loop, server)
    sender.drain()
    assert sender.sent == [("drive1", *command) for command in commands]


class _Client:
    def __init__(self) -> None:
        self.notices: list[tuple[str, str]] = []

    def add_notification(self, title: str, body: str, **_: Any) -> None:
        self.notices.append((title, body))


class _AnsweringSender(Sender):
    """Answers every command with ``answer``, as the model's action returned it."""

    def __init__(self, answer: Any) -> None:
        super().__init__()
        self.answer = answer

    def send(self, client: Any, target: str, action: str, args: dict[str, Any] | None = None,
             *, done: Callable[[Any], None] | None = None, confirm: bool = False) -> None:
        super().send(client, target, action, args, done=done, confirm=confirm)
        if done is not None:
            self.work.append(lambda: done(self.answer))


@pytest.mark.parametrize(("answer", "notices"), [
    ("not enabled (Switch on disabled) - enable torque first",
     [("drive1: jog", "drive1: not enabled (Switch on disabled) - enable torque first")]),
    (None, []),
])
def test_jog_tells_the_clicking_page_why_the_drive_does_not_move(
        loop, answer: str | None, notices: list[tuple[str, str]]) -> None:
    """Jog on a drive without torque only switched Mode to 3: no motion, no word. The model's
    answer (devices/servo/actions.py cmd_jog) now reaches the page that clicked."""
    server, sender = Server(loop), _AnsweringSender(answer)
    panel = DrivePanel(server, None, sender, lambda _client: "drive1", {})  # type: ignore[arg-type]
    frames(loop, server, lambda: panel.update(DRIVE))
    client = _Client()
    server.gui.handles["Jog"].user(client, "Jog +", click=True)  # type: ignore[arg-type]
    turn(loop, server)
    sender.drain()
    assert sender.sent == [("drive1", "jog", {"direction": 1})]
    assert client.notices == notices


@pytest.mark.parametrize(("label", "click", "command"), [
    ("Home", True, ("home", {})),
    ("Positioner", "Start", ("start", {})),
])
def test_home_and_start_tell_the_clicking_page_why_the_drive_does_not_move(
        loop, label: str, click: Any, command: tuple[str, dict[str, Any]]) -> None:
    """As Jog: after an alarm reset that left the axis released, Home and Start did nothing with
    no word (devices/servo/actions.py cmd_home / cmd_start answer as cmd_jog does)."""
    answer = "not enabled (Switch on disabled) - enable torque first"
    server, sender = Server(loop), _AnsweringSender(answer)
    panel = DrivePanel(server, None, sender, lambda _client: "drive1", {})  # type: ignore[arg-type]
    frames(loop, server, lambda: panel.update(DRIVE))
    client = _Client()
    server.gui.handles[label].user(client, click, click=True)  # type: ignore[arg-type]
    turn(loop, server)
    sender.drain()
    assert sender.sent == [("drive1", *command)]
    assert client.notices == [(f"drive1: {command[0]}", f"drive1: {answer}")]


def test_the_alarm_reset_hint_says_the_axis_waits_for_enable(loop) -> None:
    """A reset leaves the axis released until the next Enable (docs/servo-drive.md
    "Re-enabling after an alarm"); the button's hint said only "a 0 -> 1 -> 0 pulse"."""
    server = Server(loop)
    DrivePanel(server, None, Sender(), lambda _client: "drive1", {})  # type: ignore[arg-type]
    hint = server.gui.handles["Alarm reset"].hint
    assert hint == "a 0 -> 1 -> 0 pulse of the reset bit; the axis stays released until Enable"


class _RoleSender(_AnsweringSender):
    def __init__(self, answer: Any, role: Role) -> None:
        super().__init__(answer)
        self._role = role

    def role(self, client: Any) -> Role:
        return self._role


@pytest.mark.parametrize(("role", "body"), [
    (Role.TRAINEE, "alarm 16 persists: the cause persists"),
    (Role.INSTRUCTOR, "alarm 16 persists: the cause persists · injected: 16 FOLLOWING_ERROR "
                      "(Clear alarm removes it, then reset)"),
])
def test_a_refused_alarm_reset_tells_the_clicking_page_why(loop, role: Role, body: str) -> None:
    """Alarm reset with an injected alarm changed nothing on screen; the model's answer
    (cmd_alarm_reset) now reaches the page that clicked, and names the injected cause only
    to the instructor (docs/classroom.md)."""
    server, sender = Server(loop), _RoleSender("alarm 16 persists: the cause persists", role)
    panel = DrivePanel(server, None, sender, lambda _client: "drive1", {})  # type: ignore[arg-type]
    snap = {**DRIVE, "injected": [{"code": 16, "name": "FOLLOWING_ERROR"}]}
    frames(loop, server, lambda: panel.update(snap))
    client = _Client()
    server.gui.handles["Alarm reset"].user(client, None, click=True)  # type: ignore[arg-type]
    turn(loop, server)
    sender.drain()
    assert sender.sent == [("drive1", "alarm_reset", {})]
    assert client.notices == [("drive1: alarm reset refused", body)]


# The rail modules' boxes are each page's own (ClientSynced, the Module picker a ClientPick):
# tests/app/test_module_picks_per_browser.py drives them through two pages of a served rig.


# ---- the master's log style (seed 003, seed 000 §7.2-§7.4) --------------------------------
@pytest.mark.parametrize("style", LOG_STYLES[1:])
def test_the_log_style_is_the_masters(loop, style: str) -> None:
    """The dropdown commands set_log_style with the picked style and shows the master's."""
    server, sender = Server(loop), Sender()
    panel = MasterPanel(server, sender, "master")  # type: ignore[arg-type]
    master = {"log_style": LOG_STYLES[0], "log_styles": list(LOG_STYLES)}
    frames(loop, server, lambda: panel.update(master, 0))
    dropdown = server.gui.handles["Log style"]
    dropdown.user("page A", style)
    sender.drain()
    assert sender.sent == [("master", "set_log_style", {"style": style})]
    turn(loop, server)
    frames(loop, server, lambda: panel.update({**master, "log_style": style}, 0))
    assert dropdown.value == style and dropdown.sent[-1] == style
    dropdown.sent.clear()
    frames(loop, server, lambda: panel.update(master, 0))  # another page's choice won
    assert dropdown.value == LOG_STYLES[0] and dropdown.sent == [LOG_STYLES[0]]
