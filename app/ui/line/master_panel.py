"""The master panel (left panel, tab "Line"): phase, DC, frame statistics, one row per slave
(position, station address, name, state, AL status with code and text, DC, whether it answers,
counters),
each slave's ESC error counters per port (docs/ethercat-master.md "Damaged cable") and the
master's log in the style picked in the "Log style" dropdown (seed 003 and the FastCAT
seed §7.2-§7.4 styles; the master renders the lines, ``set_log_style``).

Everything shared is what a real master observes (docs/ethercat-master.md "What the master
knows"); the snapshot's ``injected`` (the cables that are out and at which end, the slaves off,
the DC fault, each lost slave's cause) goes to the status table's Injected / Causes rows, the
instructor's only (RoleHtml).

Read with ``.get()`` defaults: a master without DC or counters still gets its table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import viser

from app.ui.commands import CommandSender
from app.ui.line.cables import pulled_text
from app.ui.panels.per_client import RoleHtml, instructor_for
from app.ui.panels.widgets import Synced
from app.ui.repeats import Run, collapse_repeats, repeat_suffix
from app.ui.style import badge, clock, esc, kv_table
from devices.ethercat import AL_STATUS_ERROR_FLAG, al_status_name, describe_al_status_code
from devices.events import US_PER_S
from devices.master.view import phase_text

LOG_ROWS = 40
NBSP = "\u00a0"  # between a number and its unit: a narrow cell wraps them together
LOG_STYLES = ("twincat", "sirio", "pegaso", "aitraceprint")
DC_TONE = {"COMPENSATING": "ok", "NOT_SYNCHRONIZED": "bad", "IDLE": "muted"}


def state_badge(slave: Mapping[str, Any], target: str | None = None) -> str:
    state = slave.get("state")
    if state is None or slave.get("present") is False:
        return badge("not seen", "bad")
    requested = slave.get("requested")
    error = int(slave.get("al_status", 0)) & AL_STATUS_ERROR_FLAG or slave.get("al_status_code")
    tone = "bad" if error else ("ok" if state == (target or requested or state) else "warn")
    text = state if requested in (None, state) else f"{state} -> {requested}"
    return badge(text, tone)


def al_cell(slave: Mapping[str, Any]) -> str:
    if slave.get("state") is None:  # not on the line: nothing was read
        return '<span class="fr-muted">-</span>'
    status = int(slave.get("al_status", 0))
    code = int(slave.get("al_status_code", 0))
    text = slave.get("al_status_text") or describe_al_status_code(code)
    # A coupler code's name may break after an underscore, never inside a letter run:
    # "MISSING_NODE_ANSWER" is wider than the column (tests/browser/test_table_wrapping.py).
    code_html = esc(f"0x{code:04X} {text}").replace("_", "_<wbr>")
    if code:
        code_html = f'<span class="fr-line-bad">{code_html}</span>'
    return f"0x{status:04X} {esc(al_status_name(status))}<br>{code_html}"


def seen_cell(slave: Mapping[str, Any]) -> str:
    """Whether the slave answers the master's frames: all the master knows of a slave it lost
    (why is the instructor's Causes row)."""
    present = slave.get("present")
    if present is None:
        return '<span class="fr-muted">-</span>'
    return badge("yes", "ok") if present else badge("no", "bad")


def counters_cell(slave: Mapping[str, Any]) -> str:
    """"10/2/1/13"; when the column is too narrow it may wrap after a slash (<wbr>), never
    inside a number (the audit saw "10/2/1/1" over "3")."""
    c = slave.get("counters") or {}
    numbers = (c.get("lost_frames", 0), c.get("wkc_errors", 0), c.get("emergencies", 0),
               c.get("state_changes", 0))
    return "/<wbr>".join(esc(n) for n in numbers)


def slaves_table(slaves: Sequence[Mapping[str, Any]], target: str | None = None) -> str:
    rows = []
    for i, s in enumerate(slaves):
        dc = s.get("dc")
        rows.append(
            f"<tr><td>{esc(s.get('position', i))}<br>{esc(s.get('station_address', '?'))}</td>"
            f"<td>{esc(s.get('name', s.get('device', '?')))}<br>{state_badge(s, target)}</td>"
            f"<td>{al_cell(s)}</td>"
            f"<td>{'-' if dc is None else ('yes' if dc else 'no')}</td>"
            f"<td>{seen_cell(s)}</td><td>{counters_cell(s)}</td></tr>")
    body = "".join(rows) or '<tr><td colspan="6" class="fr-muted">no slaves</td></tr>'
    # Widths so that the longest word of each column fits at the 400 px left panel (words
    # wrap whole, tests/browser/test_table_wrapping.py): "(SelemaDriveECAT)" in Name,
    # "Synchronization" in AL status code (0x001A; it broke after "Synchronizat"), "Seen"
    # and its "yes" / "no", "10/2/1/13" in Cnt.
    return ('<table class="fr-log fr-line" id="fr-line-slaves"><colgroup><col style="width:9%">'
            '<col style="width:29%"><col style="width:27%"><col style="width:7%">'
            '<col style="width:11%"><col style="width:17%"></colgroup><thead><tr>'
            "<th>Pos<br>Addr</th><th>Name<br>State</th><th>AL status<br>code</th><th>DC</th>"
            '<th title="the slave answers the frames of the master">Seen</th>'
            '<th title="lost frames / WKC errors / emergencies / state '
            f'changes">Cnt</th></tr></thead><tbody>{body}</tbody></table>')


def _port_cell(errors: Mapping[str, Any], port: int) -> str:
    """``invalid/forwarded/lost link`` of one port, marked when the port saw anything."""
    numbers = [int((errors.get(key) or [0, 0])[port]) for key in
               ("invalid", "forwarded", "lost_link")]
    text = "/<wbr>".join(esc(n) for n in numbers)
    return f'<span class="fr-line-bad">{text}</span>' if any(numbers) else text


def esc_errors_table(slaves: Sequence[Mapping[str, Any]]) -> str:
    """One row per slave: its ESC's counters at port 0 (IN) and port 1 (OUT), and the
    processing unit's. The slave with invalid frames on port 0 sits right behind the bad
    cable, the one with invalid frames on port 1 right before it."""
    rows = []
    for i, s in enumerate(slaves):
        errors = s.get("esc_errors")
        name = f"{esc(s.get('position', i))} {esc(s.get('name', s.get('device', '?')))}"
        if errors is None:
            cells = '<td class="fr-muted">-</td>' * 3
        else:
            epu = int(errors.get("epu", 0))
            epu_html = f'<span class="fr-line-bad">{epu}</span>' if epu else "0"
            cells = (f"<td>{_port_cell(errors, 0)}</td><td>{_port_cell(errors, 1)}</td>"
                     f"<td>{epu_html}</td>")
        rows.append(f"<tr><td>{name}</td>{cells}</tr>")
    body = "".join(rows) or '<tr><td colspan="4" class="fr-muted">no slaves</td></tr>'
    legend = "invalid frames (0x0300) / forwarded (0x0308) / lost links (0x0310)"
    return ('<table class="fr-log fr-line" id="fr-line-esc-errors"><colgroup>'
            '<col style="width:40%"><col style="width:22%"><col style="width:22%">'
            '<col style="width:16%"></colgroup><thead><tr><th>ESC errors</th>'
            f'<th title="{legend}">Port 0 IN</th><th title="{legend}">Port 1 OUT</th>'
            '<th title="processing unit errors (0x030C)">PU</th></tr></thead>'
            f"<tbody>{body}</tbody></table>")


def dc_text(dc: Mapping[str, Any]) -> str:
    if not dc:
        return '<span class="fr-muted">not reported</span>'
    state = str(dc.get("state", "-"))
    out = badge(state, DC_TONE.get(state, "warn"))
    if "deviation_ns" in dc:
        # None: not measured (IDLE, the master's clock independent of the slaves, seed 003).
        deviation = dc["deviation_ns"]
        measured = "not measured" if deviation is None else f"{deviation}{NBSP}ns"
        out += esc(f" deviation {measured} / window {dc.get('window_ns', '?')}{NBSP}ns")
    return out


def title(master: Mapping[str, Any], t_us: int) -> str:
    """``EtherCAT master · master · t = 12.3 s``: its own handle, as the state panel's."""
    return (f'<p class="fr-title"><b>EtherCAT master</b> · {esc(master.get("id", "master"))}'
            f' · {clock(t_us / US_PER_S)}</p>')


def pulled_cables(master: Mapping[str, Any]) -> str:
    """Each cable that is out, as the snapshot has it (plugged only when both ends are, and
    which end a slave's own plug has out): "2 trscat -> cpx pulled at trscat OUT"; "" when
    every cable is in."""
    return "<br>".join(
        esc(f"{c.get('index', i)} {c.get('from', '?')} -> {c.get('to', '?')} {pulled_text(c)}")
        for i, c in enumerate(master.get("cables") or []) if not c.get("plugged", True))


def injected_text(master: Mapping[str, Any]) -> str:
    """What the instructor made of the line (the snapshot's ``injected`` and ``cables``): the
    cables that are out, the slaves off, the DC fault; "" when nothing is."""
    injected = master.get("injected") or {}
    names = [str(s.get("device", i)) for i, s in enumerate(master.get("slaves") or [])]
    parts = [pulled_cables(master)] if pulled_cables(master) else []
    parts += [esc(f"{i} {names[i] if i < len(names) else '?'} off")
              for i, on in enumerate(injected.get("powered") or []) if not on]
    if injected.get("dc_fault"):
        parts.append(esc(f"DC fault {injected['dc_fault']}"))
    return "<br>".join(parts)


def causes_text(master: Mapping[str, Any]) -> str:
    """Why each lost slave is lost, as the simulator knows it ("2: cable 2 pulled")."""
    lost = (master.get("injected") or {}).get("lost") or []
    return "<br>".join(esc(f"{c.get('position', '?')}: {c.get('cause', '?')}") for c in lost)


def phase_cell(master: Mapping[str, Any]) -> str:
    """The phase's word in the badge, then what it leaves out (``phase_note``) as text in the
    warning colour, as the master's body in the 3D view shows them: "[running] 2 DC slaves
    held in SAFEOP". The whole sentence in the badge broke it over two lines at the 400 px
    panel (tests/browser/test_table_wrapping.py); the text after it wraps between words."""
    phase, note = str(master.get("phase", "-")), str(master.get("phase_note") or "")
    mode = " (external master)" if master.get("external") else ""
    # "running" with slaves lost or held is not all well: the warning colour (ethercat-master.md).
    tone = "ok" if phase == "running" and not note else "warn"
    note_html = f' <span class="fr-line-warn">{esc(note)}</span>' if note else ""
    return badge(phase_text(phase), tone) + note_html + esc(mode)


def status_table(master: Mapping[str, Any]) -> str:
    """Phase, target and the master port's link: what changes only when the line does. The
    Injected and Causes rows (only when there is one: the healthy line's panel stays as it
    was) are the instructor's (:data:`app.ui.style.CAUSE_ROWS`)."""
    rows = [("Phase", phase_cell(master)),
            ("Target", esc(master.get("target", "-"))),
            ("Link", badge("up", "ok") if master.get("link", True) else badge("down", "bad"))]
    for key, text in (("Injected", injected_text(master)), ("Causes", causes_text(master))):
        if text:
            rows.append((key, f'<span class="fr-line-bad">{text}</span>'))
    return kv_table(rows, "fr-line-master-status")


def live_table(master: Mapping[str, Any]) -> str:
    """DC and frame counters: new every frame (the deviation is drawn each cycle, a frame goes
    out each cycle). The DC state shares its cell with the deviation: one line of text that
    wraps as a whole, so it cannot sit in another handle without moving pixels. The table keeps
    the summary's id: it holds the DC state the browser tests read (tests/browser/test_line.py)."""
    stats = master.get("stats") or {}
    rows = [("DC", dc_text(master.get("dc") or {})),
            ("Frames", esc(f"{stats.get('frames', '-')} sent, {stats.get('lost_frames', 0)} "
                           f"lost, cycle {stats.get('cycle_us', '-')}{NBSP}µs"))]
    return kv_table(rows, "fr-line-master")


def _stamp(line: Mapping[str, Any]) -> str:
    return str(line.get("timestamp") or f"{float(line.get('t', 0)):.3f} s")


def log_signature(master: Mapping[str, Any]) -> tuple[Any, ...]:
    """What tells that the master's log changed (length, style, newest line) without reading
    all of it: collapsing the whole log (up to 500 lines) each frame would cost."""
    log = master.get("log") or []
    return (len(log), master.get("log_style"), log[-1].get("t") if log else None,
            log[-1].get("text") if log else None)


def _log_row(run: Run[Mapping[str, Any]]) -> str:
    text = str(run.first.get("text", "")) + repeat_suffix(run.count, _stamp(run.first),
                                                          _stamp(run.last))
    return f'<tr><td class="fr-ts">{esc(_stamp(run.first))}</td><td>{esc(text)}</td></tr>'


def log_table(lines: Sequence[Mapping[str, Any]]) -> str:
    """The master's lines as it printed them, newest first; a run of repeated lines (its
    retries) is one row, "... x12, last 14.52.31 949 ms", so the emergency before it stays in
    view."""
    runs = collapse_repeats(list(lines), key=lambda line: str(line.get("text", "")))
    rows = "".join(_log_row(run) for run in runs[-LOG_ROWS:][::-1])
    body = rows or '<tr><td colspan="2" class="fr-muted">no lines yet</td></tr>'
    return ('<div class="fr-log-wrap"><table class="fr-log" id="fr-line-log"><colgroup>'
            '<col style="width:30%"><col></colgroup><thead><tr><th>Timestamp</th>'
            f"<th>Message</th></tr></thead><tbody>{body}</tbody></table></div>")


class MasterPanel:
    def __init__(self, server: viser.ViserServer, sender: CommandSender,
                 master_id: str) -> None:
        gui = server.gui
        self._cache: dict[str, str] = {}
        # The summary is three handles stacked as the one block they replace (the title's
        # margin collapses through its bare <div>, the two tables share their column widths):
        # the time and the counters move every frame, phase, target and link seldom, and each
        # handle is rewritten only when its own text changes (benchmark 3, docs/performance.md).
        self._title = gui.add_html(title({}, 0))
        # Its Injected / Causes rows: the instructor's connections only (RoleHtml).
        self._status = RoleHtml(server, instructor_for(server), status_table({}),
                                "fr-line-master-causes")
        self._live = gui.add_html(live_table({}))
        self._slaves = gui.add_html(slaves_table([]))
        self._esc_errors = gui.add_html(esc_errors_table([]))
        self._style = gui.add_dropdown("Log style", LOG_STYLES, initial_value=LOG_STYLES[0],
                                       hint="how the master prints its log (set_log_style)")
        # The style is the master's (its snapshot's "log_style"): every page ends up showing it.
        self._style_sync = Synced(server, self._style, sender, lambda client, style: sender.send(
            client, master_id, "set_log_style", {"style": style}))
        self._log = gui.add_html(log_table([]))
        self._log_seen: tuple[Any, ...] = ()

    def _set(self, key: str, handle: Any, content: str) -> None:
        if self._cache.get(key) != content:
            handle.content = content
            self._cache[key] = content

    def update(self, master: Mapping[str, Any], t_us: int) -> None:
        styles = tuple(master.get("log_styles") or LOG_STYLES)
        if tuple(self._style.options) != styles:
            self._style.options = styles
        if master.get("log_style") in styles:
            self._style_sync.follow(master["log_style"])
        self._set("title", self._title, title(master, t_us))
        status = status_table(master)
        # Every tick, unchanged too: RoleHtml writes an instructor copy built meanwhile (the
        # redraw after a promote), and compares the text itself.
        self._status.show(status)
        self._cache["status"] = status
        self._set("live", self._live, live_table(master))
        self._set("slaves", self._slaves, slaves_table(master.get("slaves") or [],
                                                            master.get("target")))
        self._set("esc_errors", self._esc_errors, esc_errors_table(master.get("slaves") or []))
        seen = log_signature(master)
        if seen != self._log_seen:
            # Recorded once written: a failure on the way is retried at the next tick.
            self._set("log", self._log, log_table(master.get("log") or []))
            self._log_seen = seen

    def text(self, key: str) -> str:
        """What a block shows: ``title``, ``status``, ``live``, ``slaves``, ``esc_errors`` or
        ``log``."""
        return self._cache.get(key, "")
