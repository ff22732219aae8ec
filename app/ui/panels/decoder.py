"""The code decoder panel: paste a code, or pick one the rig just reported, read its meaning.

The meaning comes from :func:`app.decoder.decode` (the devices' own tables). The "Reported"
dropdown lists the latest emergencies, AL status codes and alarms of the runtime's journal,
newest first: picking one decodes it, so a code seen in the log is one click away. A newly
reported code is picked and decoded at once, unless the Code box holds a query the user typed
(the list then opens on it, where it used to open on a "(pick a reported code)" row).

The Code box, the Reported pick and the answer are each page's own (docs/dashboard.md "Several
browsers"): shared, one trainee's pasted code or pick replaced what every classmate was
reading. A page that has typed or picked nothing follows the rig's newest code, as a new page
does; the list of reported codes is the rig's, the same on every page.
"""

from __future__ import annotations

import collections
import dataclasses
import threading
from collections.abc import Iterable
from typing import Any

import viser

from app.decoder import DecodeError, Meaning, decode
from app.runtime import Runtime
from app.ui.panels.client_input import ClientMirror
from app.ui.panels.client_pick import ClientHtml
from app.ui.runs import LastLoad, RunSplitter
from app.ui.style import esc
from devices.events import AlarmChanged, AlStatusChanged, EmergencySent, Event, fmt_bytes

NONE = "(nothing reported yet)"
MAX_REPORTED = 20
RESULT_ID = "fr-decoded"


def reported_code(event: Event) -> tuple[str, str] | None:
    """(picker label, text to decode) for an event that carries a code; None otherwise. The
    time in tenths, as the rest of the dashboard: with milliseconds a FastCAT emergency's
    label was wider than the box (the result's head line repeats the whole label)."""
    at = f"{event.t_us / 1e6:.1f} s {event.device}"
    if isinstance(event, EmergencySent):
        text = f"{event.code:04X} {event.register:02X} {fmt_bytes(event.data)}".strip()
        return f"{at} emergency {text}", text
    if isinstance(event, AlStatusChanged) and event.code:
        text = f"0x{event.code:04X}"
        return f"{at} AL status code {text}", text
    if isinstance(event, AlarmChanged) and event.active:
        # code and name, as the Event log prints them: the name alone may be in two tables
        # (UNDERVOLTAGE: drive, CPX-E), and the module says where a FastCAT alarm is. The
        # label leaves the module to the reading: with it the label overflowed the box.
        where = f" module {event.module}" if event.module else ""
        text = f"alarm {event.code} {event.name}{where}" if event.name else event.code
        return f"{at} alarm {event.code} {event.name}", text
    return None


def result_html(query: str, meanings: Iterable[Meaning] | None, error: str = "") -> str:
    if error:
        body = f'<span style="color:#a11616">{esc(error)}</span>'
    elif meanings is None:
        body = ('<span class="fr-muted">Paste an emergency (FF00 81 02 00 00 04 00), an AL '
                "status code (0x8204), an EMCY or 0x603F code (8130), an SDO abort code "
                "(0x06020000), an alarm name, a line of the master's log, a 0x10F3 message or "
                "a Modbus exception (83 02), or pick a code the rig reported.</span>")
    else:
        # Each reading under the table it comes from: one number can mean several things
        # ("16": AL status 0x0016 and drive alarm 16), and the table says which device
        # would report it.
        meanings = list(meanings)
        body = "".join(
            f'<div style="margin:0 0 6px 0"><span class="fr-badge fr-muted">{esc(m.family)}'
            f"</span> <b>{esc(m.title)}</b> "
            f'<span class="fr-muted">{esc(m.source)}</span><br>'
            f"{esc(m.text)}</div>" for m in meanings)
        if len(meanings) > 1:
            tables = list(dict.fromkeys(m.family for m in meanings))
            query = f"{query} · {len(meanings)} readings, in {', '.join(tables)}"
    head = f'<div class="fr-muted">{esc(query)}</div>' if query else ""
    return f'<div id="{RESULT_ID}" style="font-size:0.82em">{head}{body}</div>'


@dataclasses.dataclass
class PageView:
    """What one page's Codes tab shows: ``code`` the Code box (None: what the page typed
    stays), ``pick`` the Reported pick, ``result`` the answer's HTML; ``typed``: the Code box
    holds the page's own query, which a newly reported code leaves on display."""

    code: str | None
    pick: str
    result: str
    typed: bool = False


class _Field(ClientMirror):
    """A Codes tab widget each page fills for itself; ``on_change(client_id, value)`` after
    each change a page makes (viser's event loop)."""

    def __init__(self, server: viser.ViserServer, handle: Any, on_change: Any) -> None:
        super().__init__(server, handle)
        self._on_change = on_change

    def changed(self, client_id: int, value: Any) -> None:
        super().changed(client_id, value)  # viser's value back to a new page's
        self._on_change(client_id, value)


class DecoderPanel:
    """``side``: the dashboard's left panel (the decoder gets a tab there); None puts it in a
    folder of the current container instead. ``last_load``: the scenario player's
    (Player.last_load): the Reported list starts afresh at each load; None for no player."""

    def __init__(self, server: viser.ViserServer, runtime: Runtime, side: Any = None,
                 last_load: LastLoad | None = None) -> None:
        self._runtime = runtime
        self._server = server
        self._seq = 0
        self._runs = RunSplitter(last_load or (lambda: (0, 0)))
        self._reported: collections.deque[tuple[str, str]] = collections.deque(
            maxlen=MAX_REPORTED)
        gui = server.gui
        container = (side.add_tab("Codes") if side is not None
                     else gui.add_folder("Code decoder", expand_by_default=False))
        with container:
            self._input = gui.add_text("Code", initial_value="")
            self._button = gui.add_button("Decode", icon=viser.Icon.SEARCH)
            self._picker = gui.add_dropdown("Reported", (NONE,), initial_value=NONE)
            self._result = gui.add_html(result_html("", None))
        self._lock = threading.Lock()  # viser's event loop (a page's change), update()
        self._default = PageView("", NONE, result_html("", None))  # a new page's
        self._views: dict[int, PageView] = {}  # the pages that typed or picked since
        self._codes = _Field(server, self._input, self._on_input)
        self._picks = _Field(server, self._picker, self._on_pick)
        self._results = ClientHtml(server, self._result)
        self._button.on_click(self._on_decode)

    @staticmethod
    def _decoded(text: str, head: str = "") -> tuple[str, list[Meaning]]:
        """The result block for ``text``, and its readings. ``head``: the line above them (a
        reported code's whole label), else the query."""
        query = text.strip()
        if not query:
            return result_html("", None), []
        try:
            meanings = decode(query)
        except DecodeError as exc:
            return result_html(query, None, str(exc)), []
        return result_html(head or query, meanings), meanings

    def show(self, text: str, head: str = "") -> list[Meaning]:
        """Decode ``text`` for every page following the rig's newest code (a page's own click
        decodes for that page); returns the readings."""
        html, meanings = self._decoded(text, head)
        with self._lock:
            self._default = dataclasses.replace(self._default, result=html)
        return meanings

    def result_for(self, client_id: int | None) -> str:
        """The answer ``client_id``'s page shows (None: a new page's)."""
        with self._lock:
            return self._view(client_id).result

    def _view(self, client_id: int | None) -> PageView:
        return self._views.get(client_id, self._default) if client_id is not None \
            else self._default

    def _on_input(self, client_id: int, value: Any) -> None:
        html, _ = self._decoded(str(value))
        with self._lock:
            self._views[client_id] = dataclasses.replace(
                self._view(client_id), code=None, result=html, typed=True)

    def _on_pick(self, client_id: int, label: Any) -> None:
        with self._lock:
            text = dict(self._reported).get(str(label))
        if text is None:  # the list's placeholder, or a code a restart took away
            return
        html, _ = self._decoded(text, str(label))
        with self._lock:
            self._views[client_id] = PageView(text, str(label), html)
        self._codes.forget(client_id)  # the code goes into the box, whatever it held

    def _on_decode(self, event: viser.GuiEvent) -> None:
        """Decode: what the clicking page's Code box holds, for that page."""
        client_id = event.client_id
        html, _ = self._decoded(str(self._codes.value_for(client_id)))
        with self._lock:
            self._views[client_id] = dataclasses.replace(self._view(client_id), result=html)

    # ---- the dashboard's update thread -----------------------------------------------------
    def update(self) -> None:
        """Take the codes of the events journalled since the last call; show each page its
        view."""
        self._seq, events = self._runtime.events_since(self._seq)
        split = self._runs.split(self._seq, events)
        restarted = split is not None
        if split is not None:  # a scenario load: only the new run's codes
            events = split[1]
        fresh: list[tuple[str, str]] = []
        for event in events:
            found = reported_code(event)
            if found is not None:
                fresh.append(found)
        if fresh:
            self._report(fresh, restarted)
        elif restarted:
            with self._lock:
                self._reported.clear()
                self._default.pick = NONE
                for view in self._views.values():
                    view.pick = NONE
            self._options((NONE,))
        self._show()

    def _report(self, fresh: list[tuple[str, str]], restarted: bool) -> None:
        """Newly reported codes: listed newest first; the newest is picked and decoded on
        every page but one whose Code box holds its own query (it keeps its pick)."""
        with self._lock:
            if restarted:
                self._reported.clear()
            for label, text in fresh:
                # One option per label, the newest: viser's dropdown (a Mantine Select)
                # throws on a duplicate option once shown, and React then blanks the whole
                # page for good (a replayed scenario reported "6.0 s fastcat emergency ..."
                # a second time).
                for old in [r for r in self._reported if r[0] == label]:
                    self._reported.remove(old)
                self._reported.append((label, text))
            labels = [label for label, _ in reversed(self._reported)]
            newest, text = labels[0], self._reported[-1][1]
        html, _ = self._decoded(text, newest)
        with self._lock:
            self._default = PageView(text, newest, html)
            for client_id, view in list(self._views.items()):
                if not view.typed:  # follows the newest code again
                    del self._views[client_id]
                elif view.pick not in labels:
                    view.pick = newest
        self._options(tuple(labels))

    def _options(self, labels: tuple[str, ...]) -> None:
        """The list, on every page. The server's value goes first: viser sends every page
        the first option when its value is not among the new ones, over each page's own."""
        self._picker._impl.value = self._default.pick
        self._picker.options = labels

    def _show(self) -> None:
        clients = self._server.get_clients()
        with self._lock:
            # A page that left: its view goes (a change of its may come after viser's
            # disconnect callback, so not there)
            for gone in set(self._views) - set(clients):
                del self._views[gone]
            default, views = dataclasses.replace(self._default), dict(self._views)

        def view(client_id: int | None) -> PageView:
            return views.get(client_id, default) if client_id is not None else default

        self._codes.follow_each(lambda c: view(c).code)
        self._picks.follow_each(lambda c: view(c).pick)
        self._results.show(lambda c: view(c).result)
