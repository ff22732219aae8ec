"""The Drive tab's text: state, both status words bit by bit, control words, the drive's log.

What a commissioning engineer reads off a servo drive (seed 004; docs/servo-drive.md): the CiA
402 state and the 7-segment display, the mode, position / velocity / following error, the
alarm with its description and effect, the hardware consents TEN / IEN, the CN2 outputs and
the axis switches; then the register-mode status word R05 (ch. 1 quick reference, names per
mode) and the CiA 402 statusword 0x6041 (ch. 4) bit by bit, in the model's words (the bit
tables are devices/servo/control.py's and ds402.py's). Pure functions of the snapshot, and
small panels that rewrite their HTML only when it changes.
"""

from __future__ import annotations

import collections
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import viser

from app.modbus.line import ServedLine
from app.ui.drive.bus_state import fieldbus_rows
from app.ui.panels.client_pick import PickedHtml
from app.ui.panels.per_client import InstructorHtml, instructor_for, split_instructor
from app.ui.style import badge, clock, esc, kv_table
from devices.events import US_PER_S, AlarmChanged, EmergencySent, Event, LogLine, StateChanged
from devices.servo import control, ds402
from devices.servo.actions import names_a_cause
from devices.servo.alarms import EFFECT_TEXT, Effect, alarm_in_emergency
from devices.servo.parameters import FIELDBUS_NAMES
from devices.servo.registers import MODE_NAMES

LOG_ROWS = 12


def mode_text(mode: Any) -> str:
    try:
        return f"{int(mode)} {MODE_NAMES[int(mode)]}"
    except (KeyError, TypeError, ValueError):
        return str(mode)


def fieldbus_text(snap: Mapping[str, Any], slave: Mapping[str, Any] | None = None,
                  modbus: ServedLine | None = None) -> str:
    """How a master reaches the drive: its node (c7) on Modbus or CANopen; on EtherCAT the
    station address its slave on the line has, since the master addresses it by its place on
    the line and c7 is not used (seed 004 ch. 5 "Parametrizzazione EtherCAT per drive").
    ``modbus``: the line the rig serves (Runtime.modbus): the drive is an RTU slave, the rig
    speaks the framing and port said there (docs/modbus.md)."""
    bus = str(snap.get("fieldbus", "?"))
    name = FIELDBUS_NAMES.get(bus, bus)
    if bus == "ethercat":
        address = (slave or {}).get("station_address")
        return f"{name} station {address}" if address else f"{name} (c7 not used)"
    node = f"{name} node {snap.get('node_id', '?')}"
    return f"{node} · {modbus.words()}" if bus == "modbus" and modbus is not None else node


def title(drive_id: str, snap: Mapping[str, Any], t_us: int,
          slave: Mapping[str, Any] | None = None, modbus: ServedLine | None = None) -> str:
    """``drive · Modbus RTU node 1 · served as Modbus TCP on :5020 · t = 12.3 s`` (tenths:
    stable in a paused rig); ``slave``: the snapshot of the drive's CoE slave, when it is on
    the EtherCAT line; ``modbus``: the Modbus line as the rig serves it, if it does."""
    bus = fieldbus_text(snap, slave, modbus)
    return (f'<p class="fr-title"><b>{esc(drive_id)}</b> · {esc(bus)} · '
            f'{clock(t_us // 100_000 / 10)}</p>')


def state_badge(snap: Mapping[str, Any]) -> str:
    if not snap.get("powered"):
        return badge("power off", "muted")
    state = str(snap.get("ds402_state", "?"))
    tone = "ok" if state == "Operation enabled" else "bad" if "ault" in state else "warn"
    html = badge(state, tone)
    if snap.get("saving"):
        html += " " + badge("saving to flash", "warn")
    elif snap.get("save_pending"):
        html += ' <span class="fr-muted">save waits for torque off or IEN low</span>'
    return html


# After an alarm reset with Ten_cmd held R00 still reads "Ten_cmd, Ien_cmd", yet the drive waits
# for a fresh one (docs/servo-drive.md "Re-enabling after an alarm"): Home, Move and Start do
# nothing until then, so the row says what to press
REENABLE_NOTE = ("the alarm reset left the axis released (Ten_cmd held): press Enable "
                 "(R00 = 0, then 3)")


def effect_text(effect: Any) -> str:
    """The snapshot's effect in a trainee's words, as the Codes tab words it: its value is the
    model's note on the seed ("none printed: stop on ..."), which read as a second state."""
    try:
        return EFFECT_TEXT[Effect(effect)]
    except ValueError:
        return str(effect)


def alarm_html(snap: Mapping[str, Any]) -> str:
    alarm = snap.get("alarm")
    if not alarm:
        return badge("none", "ok")
    name = f"{alarm.get('code')} {alarm.get('name', '')}"
    html = (f"{badge(name, 'bad')}<br>{esc(alarm.get('description', ''))} "
            # a dash, not brackets: the effect's own words end in "(torque off)"
            f"<span class=\"fr-muted\">— {esc(effect_text(alarm.get('effect', '')))}</span>")
    others = [a for a in snap.get("alarms") or [] if a != alarm.get("code")]
    if others:
        html += f'<br><span class="fr-muted">also latched: {esc(others)}</span>'
    return html


def injected_names(injected: Iterable[Mapping[str, Any]]) -> str:
    """``"16 FOLLOWING_ERROR"``: the alarm causes an instructor injected (snapshot
    ``injected``), "" when none."""
    return ", ".join(f"{i.get('code', '?')} {i.get('name', '')}".strip() for i in injected)


def _on(flag: Any, on: str = "on", off: str = "off") -> str:
    return on if flag else off


def state_rows(snap: Mapping[str, Any], node: Mapping[str, Any] | None = None,
               slave: Mapping[str, Any] | None = None) -> list[tuple[str, str]]:
    """The state table; ``node`` / ``slave``: the snapshots of the drive's CANopen node and
    EtherCAT slave, if it has them (their NMT / ESM state rows, :mod:`bus_state`)."""
    outputs = snap.get("outputs") or {}
    limits = snap.get("limits") or {}
    velocity = float(snap.get("velocity", 0.0))
    fe = float(snap.get("following_error", 0.0))
    # Only the mode in force has a target: R09 in the positioner, the speed set-point in speed
    # control (the model's, ch. 2 "Select"); R09 stays at the last move's in any other mode.
    mode = snap.get("mode")
    position = f"<b>{esc(snap.get('position_counts', 0))}</b>"
    if mode in control.POSITIONER:
        position += f" <span class=\"fr-muted\">target {esc(snap.get('target', 0))}</span>"
    speed = esc(f"{velocity:.0f} u/s · following error {fe:.1f}")
    if "speed_set_point" in snap:
        target = float(snap["speed_set_point"])
        speed += f' <span class="fr-muted">target {target:.0f} u/s</span>'
    if snap.get("homed"):
        position += " " + badge("homed", "ok")
    consents = f"TEN {_on(snap.get('ten'))} · IEN {_on(snap.get('ien'))}"
    # A jammed load is an injected physical cause (the instructor's Load jammed box): an
    # instructor's row too, a trainee reads its symptoms only. Only while jammed, as the
    # badge it was in the TEN / IEN row.
    causes = [("Causes", badge("load jammed", "bad"))] if snap.get("jammed") else []
    reenable = f'<br><span class="fr-next">{esc(REENABLE_NOTE)}</span>' \
        if snap.get("released_by_reset") and snap.get("powered") else ""
    return [
        ("CiA 402 state", state_badge(snap) + ' <span class="fr-muted">display</span> '
         f'<b>{esc(snap.get("display", "") or "(dark)")}</b>' + reenable),
        *fieldbus_rows(snap, node, slave),
        ("Mode", esc(mode_text(snap.get("mode")))),
        ("Position", position),
        ("Velocity", speed),
        ("Alarm", alarm_html(snap)),
        # The instructor's (style.CAUSE_ROWS): without it an injected alarm's refused reset
        # read "persists" with no word of why (docs/classroom.md hides it from trainees).
        ("Injected", esc(injected_names(snap.get("injected") or []))
         or '<span class="fr-muted">none</span>'),
        ("TEN / IEN", esc(consents)),
        *causes,
        # CN2's four outputs in pin order (seed 004 ch. 2): 12, 13 (R50 bit 1 only), 15, 16
        ("Outputs", esc(f"End of Job {_on(outputs.get('end_of_job'))} · pin 13 "
                        f"{_on(outputs.get('out1'))} · Near to target "
                        f"{_on(outputs.get('near_target'))} · Brake "
                        f"{_on(outputs.get('brake'), 'released', 'held')}")),
        ("Switches", esc(f"NL {_on(limits.get('neg'))} · home {_on(limits.get('home'))} · "
                         f"PL {_on(limits.get('pos'))}")),
    ]


# ---- status and control words, bit by bit --------------------------------------------------
def bit_grid(caption: str, value: int, names: Mapping[int, tuple[str, str]],
             bits: int, alert: Iterable[int] = (), columns: int = 4) -> str:
    """A grid of ``bits`` cells, bit 0 first: number and short name, lit when set.
    ``names`` maps a bit to (short text, tooltip)."""
    alert = set(alert)
    cells = []
    for bit in range(bits):
        short, full = names.get(bit, ("", f"bit {bit}"))
        on = bool(value >> bit & 1)
        cls = ("fr-on" + (" fr-alert" if bit in alert else "")) if on else ""
        cells.append(f'<td class="{cls}" title="{esc(full)}"><b>{bit}</b>{esc(short)}</td>')
    rows = "".join("<tr>" + "".join(cells[i:i + columns]) + "</tr>"
                   for i in range(0, bits, columns))
    return (f'<table class="fr-bits"><caption>{esc(caption)} '
            f"<span>0x{value:0{(bits + 3) // 4}X}</span></caption>{rows}</table>")


def r05_names(mode: int) -> dict[int, tuple[str, str]]:
    return {bit: (name, f"{name}: {control.STATUS_BIT_MEANING.get(name, name)}")
            for bit, name in control.status_bit_names(mode).items()}


def r05_alert(mode: int) -> set[int]:
    return {bit for bit, name in control.status_bit_names(mode).items()
            if name in control.STATUS_ERROR_NAMES}


def statusword_names(mode: int) -> dict[int, tuple[str, str]]:
    names = {bit: (short, ds402.STATUSWORD_BITS[bit])
             for bit, short in ds402.STATUSWORD_SHORT.items()}
    for bit, text in control.statusword_mode_names(mode).items():
        names[bit] = (text, f"{ds402.STATUSWORD_BITS[bit]}: {text}")
    return names


def statusword_alert(mode: int) -> set[int]:
    return set(control.statusword_error_bits(mode))


def set_bits(value: int, names: Mapping[int, str]) -> str:
    on = [names.get(bit, f"bit {bit}") for bit in range(16) if value >> bit & 1]
    return ", ".join(on) or "none"


def control_rows(snap: Mapping[str, Any]) -> list[tuple[str, str]]:
    mode = int(snap.get("mode", 1))
    r00 = int(snap.get("control_register", 0))
    cw = int(snap.get("controlword", 0))
    return [
        ("R00 control", esc(f"0x{r00:04X}: {set_bits(r00, control.control_bit_names(mode))}")),
        ("0x6040", esc(f"0x{cw:04X}: {set_bits(cw, ds402.CONTROLWORD_BITS)}")),
    ]


def words_html(snap: Mapping[str, Any]) -> str:
    mode = int(snap.get("mode", 1))
    return (bit_grid("R05 status word", int(snap.get("status_register", 0)), r05_names(mode),
                     8, r05_alert(mode))
            + bit_grid("0x6041 statusword", int(snap.get("statusword", 0)),
                       statusword_names(mode), 16, statusword_alert(mode))
            + kv_table(control_rows(snap), "fr-drive-cw"))


# ---- the drive's own log --------------------------------------------------------------------
def event_text(event: Event) -> tuple[str, bool] | None:
    """A drive or CANopen-node event in words, and whether it reads as an error."""
    if isinstance(event, StateChanged):
        machine = {"": "CiA 402", "nmt": "NMT"}.get(event.machine, event.machine)
        return f"{machine}: {event.from_state} -> {event.to_state}", False
    if isinstance(event, AlarmChanged):
        verb = "raised" if event.active else "cleared"
        return f"alarm {event.code} {event.name} {verb}", event.active
    if isinstance(event, EmergencySent):
        record = event.to_record()
        text = f"EMCY {record['code']} register {record['register']} data {record['data']}"
        # The alarm byte is hex there (16 reads "10"); the drive numbers alarms in decimal.
        alarm = alarm_in_emergency(event.code, event.data)
        return (f"{text}: alarm {alarm.code} {alarm.name}" if alarm else text), True
    if isinstance(event, LogLine):
        return event.text, "fail" in event.text.lower()
    return None


class DriveLog:
    """Each drive's last events, newest first (the dashboard's event log shows the coupler's).

    One bounded list per drive: with one list for all, a busy drive's events pushed a quiet
    one's out, and a drive in Fault read "no drive events yet" (docs/dashboard.md).
    ``causes=False`` (a rig with trainees) leaves out the lines naming an injected cause
    ("load jammed", "cause of alarm 16 removed"): the log is one element every browser
    gets."""

    def __init__(self, rows: int = LOG_ROWS, causes: bool = True) -> None:
        self._size = rows
        self._causes = causes
        self._rows: dict[str, collections.deque[tuple[int, str, bool]]] = {}

    def add(self, events: Iterable[Event]) -> None:
        for event in events:
            found = event_text(event)
            if found is None or (not self._causes and isinstance(event, LogLine)
                                 and names_a_cause(event.text)):
                continue
            rows = self._rows.get(event.device)
            if rows is None:
                rows = self._rows[event.device] = collections.deque(maxlen=self._size)
            rows.append((event.t_us, *found))

    def html(self, device: str) -> str:
        rows = list(reversed(self._rows.get(device, ())))
        if not rows:
            return '<p class="fr-muted fr-drive-log">no drive events yet</p>'
        items = "".join(f'<li class="{"fr-err" if err else ""}">{t / US_PER_S:8.3f} s '
                        f"{esc(text)}</li>" for t, text, err in rows)
        return f'<ul class="fr-drive-log" id="fr-drive-log">{items}</ul>'

    def clear(self) -> None:
        """At a scenario load (DriveView.new_run): the new run's rows only."""
        self._rows.clear()


Pick = Callable[[int | None], str]  # the drive a page shows (None: a new page's)
DriveData = Callable[[str], tuple[Mapping[str, Any], Mapping[str, Any] | None,
                                  Mapping[str, Any] | None]]  # drive, its node, its slave


def _memo(fn: Callable[[str], str]) -> Callable[[str], str]:
    """``fn`` computed once per drive in one frame, however many pages show it."""
    made: dict[str, str] = {}

    def get(drive_id: str) -> str:
        if drive_id not in made:
            made[drive_id] = fn(drive_id)
        return made[drive_id]

    return get


class DriveStatePanel:
    """Title and state table (above the plots), as two handles: the title carries the
    simulated time and changes ten times a second, the table only when a value in it does, so
    the table is not resent with every tenth (issue 7, as ``app.ui.panels.state``). Two bare
    <div>s lay out as the one they replace (the title's margin collapses through its div).
    ``per_page``: each page shows the drive it picked (several drives)."""

    def __init__(self, server: viser.ViserServer, per_page: bool = False) -> None:
        instructor = instructor_for(server)
        self._shared = instructor.shared
        self._title = PickedHtml(server, "", per_page)
        self._table = PickedHtml(server, kv_table([("CiA 402 state", "-")], "fr-drive"),
                                 per_page)
        # The Causes and Injected rows: the instructor's connections only, each its page's
        # drive's (as RoleHtml does for one element).
        self._causes = None if self._shared else InstructorHtml(instructor)

    def update(self, pick_of: Pick, data_of: DriveData, t_us: int,
               modbus: ServedLine | None = None) -> None:
        table = _memo(lambda d: kv_table(state_rows(*data_of(d)), "fr-drive"))
        self._title.show(lambda d: title(d, data_of(d)[0], t_us, data_of(d)[2], modbus),
                         pick_of)
        self._table.show(lambda d: table(d) if self._shared
                         else split_instructor(table(d), "fr-drive-causes")[0], pick_of)
        if self._causes is not None:
            self._causes.show_each(lambda client_id: split_instructor(
                table(pick_of(client_id)), "fr-drive-causes")[1])


class StatusWordsPanel:
    """Both status words bit by bit, the control words, and the drive's log (below the
    plots)."""

    def __init__(self, server: viser.ViserServer, per_page: bool = False) -> None:
        self._words = PickedHtml(server, "", per_page)
        server.gui.add_markdown("**Drive log**")
        self._log_html = PickedHtml(server, DriveLog().html(""), per_page)
        self.log = DriveLog(causes=instructor_for(server).shared)

    def update(self, pick_of: Pick, data_of: DriveData) -> None:
        self._words.show(lambda d: words_html(data_of(d)[0]), pick_of)
        self._log_html.show(self.log.html, pick_of)
