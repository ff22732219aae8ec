"""The code decoder panel: paste a code, or pick one the rig just reported, read its meaning.

The meaning comes from :func:`app.decoder.decode` (the devices' own tables). The "Reported"
dropdown lists the latest emergencies, AL status codes and alarms of the runtime's journal,
newest first: picking one decodes it, so a code seen in the log is one click away. A newly
reported code is picked and decoded at once, unless the Code box holds a query the user typed
(the list then opens on it, where it used to open on a "(pick a reported code)" row). The
answer is server-level, like the rest of the dashboard: every browser sees the last decoded
code.
"""

from __future__ import annotations

import collections
from collections.abc import Iterable
from typing import Any

import viser

from app.decoder import DecodeError, Meaning, decode
from app.runtime import Runtime
from app.ui.panels.widgets import from_user
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


class DecoderPanel:
    """``side``: the dashboard's left panel (the decoder gets a tab there); None puts it in a
    folder of the current container instead. ``last_load``: the scenario player's
    (Player.last_load): the Reported list starts afresh at each load; None for no player."""

    def __init__(self, server: viser.ViserServer, runtime: Runtime, side: Any = None,
                 last_load: LastLoad | None = None) -> None:
        self._runtime = runtime
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
        self._input.on_update(self._on_input)
        self._button.on_click(lambda event: self.show(str(self._input.value)))
        self._picker.on_update(self._on_pick)
        self._typed = False  # the Code box holds the user's own query: new codes leave it

    def show(self, text: str, head: str = "") -> list[Meaning]:
        """Decode ``text`` into the result block (what a click does); returns the readings.
        ``head``: the line above them (a reported code's whole label), else the query."""
        query = text.strip()
        if not query:
            self._result.content = result_html("", None)
            return []
        try:
            meanings = decode(query)
        except DecodeError as exc:
            self._result.content = result_html(query, None, str(exc))
            return []
        self._result.content = result_html(head or query, meanings)
        return meanings

    def _on_input(self, event: viser.GuiEvent) -> None:
        if from_user(event):
            self._typed = True
            self.show(str(self._input.value))

    def _on_pick(self, event: viser.GuiEvent) -> None:
        if from_user(event):
            self._show_reported(str(self._picker.value))

    def _show_reported(self, label: str) -> None:
        text = dict(self._reported).get(label)
        if text is not None:
            self._typed = False
            self._input.value = text
            self.show(text, label)

    # ---- the dashboard's update thread -----------------------------------------------------
    def update(self) -> None:
        """Take the codes of the events journalled since the last call."""
        self._seq, events = self._runtime.events_since(self._seq)
        split = self._runs.split(self._seq, events)
        restarted = split is not None
        if split is not None:  # a scenario load: only the new run's codes
            self._reported.clear()
            events = split[1]
        fresh: list[tuple[str, str]] = []
        for event in events:
            found = reported_code(event)
            if found is not None:
                fresh.append(found)
        if not fresh:
            if restarted:
                self._picker.options = (NONE,)
                self._picker.value = NONE
            return
        for label, text in fresh:
            # One option per label, the newest: viser's dropdown (a Mantine Select) throws on
            # a duplicate option once shown, and React then blanks the whole page for good
            # (a replayed scenario reported "6.0 s fastcat emergency ..." a second time).
            for old in [r for r in self._reported if r[0] == label]:
                self._reported.remove(old)
            self._reported.append((label, text))
        labels = [label for label, _ in reversed(self._reported)]
        current = str(self._picker.value)
        self._picker.options = tuple(labels)
        if self._typed:  # the user's query stays on display
            self._picker.value = current if current in labels else labels[0]
        else:
            self._picker.value = labels[0]
            self._show_reported(labels[0])
