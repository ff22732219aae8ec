"""The event log, laid out like the TwinCAT logger: Server (port) | Timestamp | Message.

Rows come from two places: the built-in master's logger lines (its snapshot's ``log``, with
the AMS port 65535 and the TwinCAT timestamp the master printed) and the device events a
technician also wants in the same list (ESM state changes, emergencies, alarms raised and
cleared, scenario captions), stamped with the same clock. Newest first, bounded; a run of
repeated rows (a master's retries) is one row with a count (app/ui/repeats.py). A scenario load
puts the clock back to 0 on a factory-fresh rig: the log starts afresh there (the dashboard
calls :meth:`EventLogPanel.new_run` where the load splits its batch, app/ui/runs.py), with a
row saying so, since the earlier rows would sort among (or, stamped later, above) the new run's.
"""

from __future__ import annotations

import collections
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import viser

from app.ui.line.master_panel import log_signature
from app.ui.repeats import collapse_repeats, repeat_suffix
from app.ui.style import esc
from devices.events import (
    US_PER_S,
    AlarmChanged,
    Caption,
    EmergencySent,
    EsmLogLine,
    Event,
    LogLine,
    StateChanged,
)

MAX_ROWS = 50
_ERROR_WORDS = ("emergency", "failed", "abnormal", "aborted", "error")

# simulated microseconds -> "12/11/2019 14.51.30 421 ms"
Timestamp = Callable[[int], str]


@dataclass(frozen=True)
class LogRow:
    t_us: int
    order: int  # arrival order, to keep lines of one instant as they were logged
    server: str
    timestamp: str
    message: str
    error: bool


# The name of a device kind's main state machine (StateChanged.machine == ""), when it is not
# the EtherCAT ESM: a servo drive's is CiA 402 (its EtherCAT side reports machine "esm").
_MAIN_MACHINE = {"servo": "CiA 402"}
# Device kinds whose own log lines are rows here: the FastCAT logs only what a trainee must see
# (a refused Reset fault); the drives' lines (homing, modes, flash) go to their own tab's log.
_LOGGED_KINDS = frozenset({"fastcat"})


def event_message(event: Event, device_kind: str = "") -> tuple[str, bool] | None:
    """The log text of a device event, and whether it reads as an error; None to skip it.
    ``device_kind`` (the rig's ``describe()`` kind) names the device's main state machine."""
    record = event.to_record()
    if isinstance(event, StateChanged):
        if event.machine == "cnf_button":
            return f"CNF button {event.to_state}", False
        if event.machine == "esm":
            return f"ESM state change '{event.from_state}' -> '{event.to_state}'", False
        main = _MAIN_MACHINE.get(device_kind, "")
        if event.machine or main:
            what = ("CNF procedure" if event.machine == "cnf" else event.machine or main)
            return f"{what}: {event.from_state} -> {event.to_state}", False
        return f"ESM state change '{event.from_state}' -> '{event.to_state}'", False
    if isinstance(event, EmergencySent):
        return (f"Emergency sent (code {record['code']}, register {record['register']}, "
                f"data {record['data']})"), True
    if isinstance(event, AlarmChanged):
        where = f" module {event.module}" if event.module else ""
        verb = "raised" if event.active else "cleared"
        return f"alarm {event.code} {event.name}{where} {verb}", event.active
    if isinstance(event, Caption):
        return f"» {event.text}", False
    if isinstance(event, EsmLogLine):  # an AL control request a slave ignored: every kind
        return event.text, True
    if isinstance(event, LogLine) and device_kind in _LOGGED_KINDS:
        return event.text, "refused" in event.text.lower()
    return None


def collapse_rows(rows: Iterable[LogRow]) -> list[LogRow]:
    """Rows oldest first -> newest first, each run of repeated rows (same server and message)
    as one: the first row's timestamp, "... x12, last 14.52.31 949 ms" after the message."""
    runs = collapse_repeats(list(rows), key=lambda r: (r.server, r.message))
    return [replace(run.first, message=run.first.message
                    + repeat_suffix(run.count, run.first.timestamp, run.last.timestamp))
            for run in reversed(runs)]


def render_rows(rows: Iterable[LogRow]) -> str:
    body = "".join(
        f'<tr class="{"fr-err" if r.error else ""}"><td class="fr-srv">{esc(r.server)}</td>'
        f'<td class="fr-ts">{"<br>".join(esc(p) for p in r.timestamp.split(" ", 1))}</td>'
        f"<td>{esc(r.message)}</td></tr>"
        for r in rows)
    if not body:
        body = '<tr><td colspan="3" class="fr-muted">no messages yet</td></tr>'
    # Timestamp column: the date and the time of day on two lines, as narrow as they get.
    # Server column: 7em holds a 10-character id ("drive_ecat", 64 px at the log's 10.7 px
    # font, + 8 px padding; static/rigs/' longest is 8); 4.8em clipped "scenario" to "scenari".
    return ('<div class="fr-log-wrap"><table class="fr-log" id="fr-log"><colgroup>'
            '<col style="width:7em"><col style="width:10.4em"><col></colgroup><thead><tr>'
            '<th>Server</th><th>Timestamp</th>'
            f'<th>Message</th></tr></thead><tbody>{body}</tbody></table></div>')


def new_run_message(title: str) -> str:
    """The row that starts the log at a scenario load (the clock at 0)."""
    what = f"scenario '{title}' started" if title else "the rig restarted"
    return f"» {what}: the rig is factory-fresh, the clock at 0 s"


class EventLogPanel:
    def __init__(self, server: viser.ViserServer, device_kinds: Mapping[str, str],
                 timestamp: Timestamp, run_title: Callable[[], str] = str) -> None:
        """``device_kinds``: id -> kind of every device whose own events are logged (all of
        the rig's but the master, whose lines come from its snapshot's ``log``);
        ``run_title``: the loaded scenario's name ("" for none), read at :meth:`new_run`."""
        self._kinds = dict(device_kinds)
        self._timestamp = timestamp
        self._run_title = run_title
        self._device_rows: collections.deque[LogRow] = collections.deque(maxlen=MAX_ROWS)
        self._order = 0
        self._html = server.gui.add_html(render_rows([]))
        self._last = ""
        self._seen: tuple[Any, ...] = ()

    def add_events(self, events: Iterable[Event]) -> None:
        for event in events:
            if event.device not in self._kinds and not isinstance(event, Caption):
                continue
            # LEDs, log lines, reads, ... give None: a moving drive emits none of the kinds
            # kept, so the log is not flooded (and the deque keeps it bounded anyway).
            found = event_message(event, self._kinds.get(event.device, ""))
            if found is None:
                continue
            text, error = found
            self._order += 1
            self._device_rows.append(LogRow(event.t_us, self._order, event.device,
                                            self._timestamp(event.t_us), text, error))

    def new_run(self) -> None:
        """A scenario load or restart (app/player.py): the rows of the previous run go, or
        they would sit among the new run's (a load at 0 s) or, stamped later, top the
        newest-first log. The master's lines need nothing: the fresh master's log starts
        empty."""
        self._device_rows.clear()
        self._order += 1
        self._device_rows.append(LogRow(0, self._order, "scenario", self._timestamp(0),
                                        new_run_message(self._run_title()), False))

    def update(self, master_snap: Mapping[str, Any] | None) -> None:
        log = list((master_snap or {}).get("log", []))
        # The whole of the master's log, not its last rows: collapsed, its retries take a row
        # or two and the emergency before them stays in view. Read again only when it changed.
        seen = (self._order, *log_signature(master_snap or {}))
        if seen == self._seen:
            return
        rows = list(self._device_rows)
        for i, line in enumerate(log):
            text = str(line.get("text", ""))
            rows.append(LogRow(
                round(float(line.get("t", 0.0)) * US_PER_S), i - len(log),
                f"({line.get('port', '')})", str(line.get("timestamp", "")), text,
                any(w in text.lower() for w in _ERROR_WORDS)))
        # Oldest first; the master's lines of an instant come after the device's own events
        # (the master reads them a cycle later), hence the negative order for master lines
        # only breaks ties among themselves.
        rows.sort(key=lambda r: (r.t_us, r.server.startswith("("), r.order))
        content = render_rows(collapse_rows(rows)[:MAX_ROWS])
        if content != self._last:
            self._html.content = content
            self._last = content
        self._seen = seen  # once written: a failure on the way is retried at the next tick
