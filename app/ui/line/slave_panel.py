"""The slave panel (left panel, tab "Slave"): the picked slave's state, its LEDs in words
(name, colour, pattern) and its I/O, for the TRS-CAT, the CPX-E-EC and the drive's EtherCAT
side; the FastCAT has its own State tab. A click on a slave in the 3D view picks it here, on
the clicking page.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import viser

from app.ui.line.bodies import as_drawn, led_colour
from app.ui.line.io_bodies import (
    CPX_COLOURS,
    LED_WORDS,
    TRS_LEDS,
    channel_list,
    ident_text,
    module_fault_parts,
)
from app.ui.panels.client_pick import ClientHtml, ClientPick
from app.ui.panels.per_client import instructor_for, split_instructor
from app.ui.panels.state import injected_text
from app.ui.rail_scene import PATTERN_WORDS
from app.ui.style import INSTRUCTOR_CLASS, badge, esc, kv_table
from devices.canopen.emcy import REGISTER_WORDS as DRIVE_REGISTER_WORDS
from devices.cpx.catalog import IO_MODULES, ModuleKind
from devices.cpx.codes import ERROR_REGISTER_WORDS, STATUS_BITS
from devices.cpx.esm import AL_STATUS_ID_LOADED
from devices.ethercat import al_status_name, describe_al_status_code

MESSAGES = 6  # newest 0x10F3 messages shown


BIT_GROUP = 8  # bits per word of a bit string: a narrow cell wraps between words only


def bits(values: Sequence[Any]) -> str:
    """``[1, 0, 1]`` -> ``"101"`` (channel 1 first), in groups of BIT_GROUP ("10000000
    00000000"); analog values as numbers."""
    if all(isinstance(v, bool) or v in (0, 1) for v in values):
        digits = "".join("1" if v else "0" for v in values)
        return " ".join(digits[i:i + BIT_GROUP]
                        for i in range(0, len(digits), BIT_GROUP)) or "-"
    return " ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values)


def slot_values(slot: Mapping[str, Any], key: str) -> str:
    """A TRS-CAT slot's ``inputs`` / ``outputs``: bits for the bidirectional lines (a slot
    snapshot with ``lines``, seed 001 §3), one number per channel for analog and data words,
    whose 0 / 1 values ``bits`` would write as lines ("0100" for four AN-E inputs)."""
    values = slot.get(key) or []
    if "lines" in slot:
        return bits(values)
    return " ".join(str(v) for v in values) or "-"


def cpx_values(module: Mapping[str, Any], key: str) -> str:
    """A CPX-E-EC module's ``inputs`` / ``outputs``: bits for a digital module, one number per
    channel for the others (analog words, the counter's values, seed 002 Tab. 9), which
    ``bits`` would write as lines at 0 and 1 ("0000" for a 4AI-U-I at rest)."""
    values = module.get(key) or []
    mtype = IO_MODULES.get(str(module.get("type")))
    if mtype is None or mtype.kind is ModuleKind.DIGITAL:
        return bits(values)
    return " ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values) or "-"


def esm_badge(snap: Mapping[str, Any]) -> str:
    """A slave's ESM state (snapshot ``esm``), red with an AL status code, and the state the
    master requested when it is another."""
    code = int(snap.get("al_status_code", 0))
    esm, requested = snap.get("esm", "-"), snap.get("requested")
    tone = "bad" if code else ("ok" if esm == "OP" else "warn")
    return badge(str(esm), tone) + (f" (requested {esc(requested)})"
                                    if requested and requested != esm else "")


def esm_rows(snap: Mapping[str, Any]) -> list[tuple[str, str]]:
    code = int(snap.get("al_status_code", 0))
    status = int(snap.get("al_status", 0))
    text = snap.get("al_status_text") or describe_al_status_code(code)
    return [("ESM state", esm_badge(snap)),
            ("AL status", esc(f"0x{status:04X} {al_status_name(status)}")),
            ("AL status code", esc(f"0x{code:04X} {text}")),
            ("Station address", esc(snap.get("station_address", "-")))]


def led_table(leds: Sequence[tuple[str, str, str]]) -> str:
    rows = "".join(f"<tr><td>{esc(n)}</td><td>{esc(c)}</td>"
                   f"<td>{esc(PATTERN_WORDS.get(p, p))}</td></tr>" for n, c, p in leds)
    return ('<table class="fr-log" id="fr-slave-leds"><thead><tr><th>LED</th><th>Colour</th>'
            f"<th>Pattern</th></tr></thead><tbody>{rows}</tbody></table>")


def messages_table(messages: Sequence[Mapping[str, Any]]) -> str:
    if not messages:
        return '<p class="fr-muted">0x10F3: no messages</p>'
    rows = "".join(f"<tr><td>{esc(m.get('sub', ''))}</td><td>{esc(m.get('type', ''))}</td>"
                   f"<td>{esc(m.get('text_id', m.get('code', '')))}</td>"
                   f"<td>{esc(m.get('text', ''))}</td></tr>"
                   for m in list(messages)[-MESSAGES:][::-1])
    return ('<table class="fr-log" id="fr-slave-diag"><colgroup><col style="width:10%">'
            '<col style="width:15%"><col style="width:17%"><col></colgroup><thead><tr>'
            "<th>Sub</th><th>Type</th><th>Text-ID</th><th>Message (0x10F3, newest first)</th>"
            f"</tr></thead><tbody>{rows}</tbody></table>")


def alarm_text(alarm: Any) -> str:
    """``{"code": "0xA000", "name": "CONFIG_ERROR", "slot": 2}`` -> "0xA000 CONFIG_ERROR
    (slot 2)"."""
    if not isinstance(alarm, Mapping):
        return str(alarm)
    slot = alarm.get("slot")
    return (f"{alarm.get('code', '')} {alarm.get('name', '')}"
            + (f" (slot {slot})" if slot is not None else "")).strip()


# The sync unit's state (devices/trscat/sync.py SyncState) in words: FREE_RUN is also DC-SYNC
# before the master started SYNC0, so it names the local cycle, not the mode.
SYNC_STATES = {"free_run": "free-running local cycle (no SYNC0)",
               "dc_running": "on SYNC0 (DC running)",
               "sync_error": "sync error (SM events missed)",
               "sync0_lost": "SYNC0 lost (SM events without SYNC0)"}


def field_supply(snap: Mapping[str, Any]) -> str:
    """The field supply as the +24V LED judges it: the LED needs the logic supply too
    (docs/trscat.md), so a powered-off node says so instead of "ok"."""
    volts = esc(f"{snap.get('field_supply_v', '-')} V")
    if snap.get("powered") is False:
        return f"{volts} {badge('node off', 'warn')} not monitored, +24V LED off"
    return f"{volts} " + (badge("ok", "ok") if snap.get("field_ok", True)
                          else badge("alarm", "bad"))


def sync_rows(sync: Mapping[str, Any]) -> list[tuple[str, str]]:
    """The mode (0x1C32:1, which PREOP -> SAFEOP takes from Sync Control 0x0980) and the
    sync unit's state, each labelled: "DC-SYNC · free_run" read as one thing."""
    state = str(sync.get("state", "-"))
    return [("Sync mode", esc(f"{sync.get('mode', '-')} (0x1C32:1) · Sync Control 0x0980 = "
                              f"0x{int(sync.get('sync_control', 0)):04X}")),
            ("Sync state", esc(f"{SYNC_STATES.get(state, state)} · SM events missed "
                               f"{sync.get('sm_event_missed', 0)}" +
                               (" · sync error" if sync.get("sync_error") else "")))]


def slot_type(slot: Mapping[str, Any]) -> str:
    """An empty position: "- not seen", with the module the master configures there."""
    if slot.get("type") is not None:
        return esc(slot.get("type"))
    configured = slot.get("configured")
    return ("- " + badge("not seen", "bad") +
            (esc(f" (configured {configured})") if configured else ""))


def bus_text(bus: Mapping[str, Any]) -> str:
    """The TRS bus state; a latched shutdown with the one way out (docs/trscat.md: clearing
    the cause does not bring the bus back), or a trainee waits for a recovery that never
    comes."""
    state = str(bus.get("state", "-"))
    return f"{state} (latched: switch the logic supply off and on)" if bus.get("latched") \
        else state


def outputs_text(snap: Mapping[str, Any]) -> str:
    """What the outputs do: the ESM's output mode, unless the model says every slot is
    stopped ("off (bus down)": the mode still reads "normal" in OP)."""
    stopped = snap.get("outputs_stopped")
    return f"off ({stopped})" if stopped else str(snap.get("outputs_mode", "-"))


def trscat_html(snap: Mapping[str, Any]) -> str:
    leds = snap.get("leds") or {}
    sync = snap.get("sync") or {}
    bus = snap.get("trs_bus") or {}
    rows = [
        *esm_rows(snap),
        ("Logic supply", badge("on", "ok") if snap.get("powered", True)
         else badge("off", "bad") + esc(" (Vdd)")),
        ("Field supply", field_supply(snap)),
        ("TRS bus", esc(bus_text(bus))),
        *sync_rows(sync),
        ("Outputs", esc(outputs_text(snap)) +
         (" " + badge("PREOP deadlock", "bad") if snap.get("deadlocked") else "")),
        ("0xF100 diag status", esc(f"0x{int(snap.get('diag_status', 0)):02X}")),  # U8, §9.3.4
        ("Alarms", esc(", ".join(alarm_text(a) for a in snap.get("alarms") or []) or "none")),
        # the application causes, then the sync manager faults (checked at IP / PS)
        ("Injected", injected_text([*(snap.get("injected") or []),
                                    *(snap.get("injected_sm") or [])]))]
    slots = "".join(
        f"<tr><td>{esc(s.get('slot'))}</td><td>{slot_type(s)}</td>"
        f"<td>{esc(ident_text(s.get('ident', 0)))}</td>"
        f"<td>{esc(slot_values(s, 'inputs'))}</td>"
        f"<td>{esc(slot_values(s, 'outputs'))}</td></tr>" for s in snap.get("slots") or [])
    io = ('<table class="fr-log" id="fr-slave-io"><thead><tr><th>Slot</th><th>Type</th>'
          "<th>Ident</th><th>Inputs</th><th>Outputs</th></tr></thead>"
          f"<tbody>{slots}</tbody></table>")
    names = [(n, c, str(leds.get(n, "off"))) for n, c in TRS_LEDS]
    lit = [c for c in range(1, 17) if leds.get(f"I/O {c}", "off") != "off"]
    names.append(("I/O 1-16", "yellow", f"on: {', '.join(map(str, lit))}" if lit else "off"))
    diag = (snap.get("diagnosis") or {}).get("messages") or []
    return (kv_table(rows, "fr-slave-state") + led_table(names) + io + messages_table(diag))


def switches_text(switches: Mapping[str, Any]) -> str:
    """"rotary 000, I/O diagnostic interface"; with switches moved since the last start, what
    the firmware runs with and what a restart would apply (seed 002 §2.1.7)."""
    mode, rotary = switches.get("mode", "-"), switches.get("rotary_hex", "-")
    if not switches.get("pending"):
        return f"rotary {rotary}, {mode}"
    active = f"rotary {int(switches.get('active_rotary', 0)):03X}, {switches.get('active_mode')}"
    return f"active: {active}; set: rotary {rotary}, {mode}"


def id_text(snap: Mapping[str, Any]) -> str:
    """The Explicit Device ID row: while a wire master's ID request is answered the wire shows
    AL status 0x0020 and the ID at 0x0134, not the ESM's rows above (devices/cpx/device_id.py).
    """
    ident = int(snap.get("explicit_device_id", 0))
    text = esc(f"0x{ident:03X}" if ident else "0x000 (none: stored address)")
    if not snap.get("id_loaded"):
        return text
    status = int(snap.get("al_status", 0)) | AL_STATUS_ID_LOADED
    return (text + " " + badge("ID loaded", "ok") +
            esc(f" wire: 0x0130 = 0x{status:04X}, 0x0134 = 0x{ident:04X}"))


def fault_cell(module: Mapping[str, Any]) -> str:
    """A module's Fault cell (HTML, each text escaped once): what the device diagnoses for
    everyone, what is wired but not diagnosed in a span of INSTRUCTOR_CLASS, separator and
    all: an undiagnosed cause is an injected one, which no trainee's page may name
    (docs/classroom.md; the reviewer's rv3/cpx_leak.py)."""
    seen, hidden = module_fault_parts(module)
    if not hidden:
        return esc(seen)
    tail = "; ".join(hidden)
    tail = f"; {tail}" if seen else tail
    where = esc(f"module {module.get('module', '?')}")
    return esc(seen) + f'<span class="{INSTRUCTOR_CLASS}" data-where="{where}">{esc(tail)}</span>'


def held_off_note(module: Mapping[str, Any]) -> str:
    """Under a module's output image (HTML): the outputs the module holds off against it, by
    the cause the bus module diagnoses ("held off: 3 (short)"), as the module snapshot's
    "held_off" says; none named when none is diagnosed. The image keeps the PLC's value: read
    alone, 00010000 after a short on output 3 said "output 3 on" (docs/cpx-e-ec.md choice 40).
    """
    by_cause: dict[str, list[int]] = {}
    for entry in module.get("held_off") or []:
        cause = entry.get("cause")
        words = LED_WORDS.get(str(cause), str(cause)) if cause is not None else ""
        by_cause.setdefault(words, []).append(int(entry.get("channel", 0)))
    notes = [f"{channel_list(channels)} ({words})" if words else channel_list(channels)
             for words, channels in by_cause.items()]
    if not notes:
        return ""
    return f'<br><span class="fr-line-bad">{esc("held off: " + "; ".join(notes))}</span>'


def status_register_text(value: int) -> str:
    """0x1002 in seed 002 Tab. 23's words: "0x24 Error at input, Short circuit/overload"
    (bits 0-3 the module type, 4-7 the error type, bit 0 first)."""
    words = [STATUS_BITS[bit] for bit in sorted(STATUS_BITS) if value >> bit & 1]
    return f"0x{value:02X} {', '.join(words) or 'no error'}"


def cpx_html(snap: Mapping[str, Any]) -> str:
    states = snap.get("led_states") or {}
    switches = snap.get("switches") or {}
    supply = snap.get("supply") or {}
    diagnosis = snap.get("diagnosis") or {}
    rows = [
        *esm_rows(snap),
        ("Switches", esc(switches_text(switches)) +
         (" " + badge("restart to apply", "warn") if switches.get("pending") else "")),
        ("Explicit Device ID", id_text(snap)),
        ("Supply", esc(f"U_EL/SEN {supply.get('el_sen_v', '-')} V, "
                       f"U_OUT {supply.get('out_v', '-')} V")),
        # Tab. 22's names of the set bits, as 0x1002's row below reads Tab. 23's.
        ("Error register 0x1001", esc(ERROR_REGISTER_WORDS.value_text(
            int(diagnosis.get("error_register", 0))))),
        # Tab. 20 byte 3: what module type and error the diagnosis is about, next to 0x1001.
        ("Status bits 0x1002", esc(status_register_text(int(diagnosis.get("status_bits", 0))))),
        ("Injected", injected_text(snap.get("injected") or []))]
    names = [(n, str((states.get(n) or {}).get("colour", c)),
              str((states.get(n) or {}).get("pattern", "off"))) for n, c in CPX_COLOURS.items()]
    modules = "".join(
        f"<tr><td>{esc(m.get('module'))}</td><td>{esc(m.get('short', m.get('type')))}</td>"
        f"<td>{esc(cpx_values(m, 'inputs'))}</td>"
        f"<td>{esc(cpx_values(m, 'outputs'))}{held_off_note(m)}</td>"
        f"<td class=\"fr-line-bad\">{fault_cell(m)}</td></tr>"
        for m in snap.get("modules") or [])
    # "PLC out": the image the PLC wrote (RxPDO), held-off channels noted under it; a longer
    # header wrapped over three lines and pushed the module rows out of a 1280x720 view.
    io = ('<table class="fr-log" id="fr-slave-io"><thead><tr><th>#</th><th>Module</th>'
          '<th>Inputs</th><th title="the outputs as the PLC wrote them (RxPDO)">PLC out</th>'
          "<th>Fault</th></tr></thead>"
          f"<tbody>{modules}</tbody></table>")
    history = (snap.get("history") or {}).get("messages") or []
    return kv_table(rows, "fr-slave-state") + led_table(names) + io + messages_table(history)


def pdo_list(assigned: Any) -> str:
    """The PDO indexes of 0x1C12 / 0x1C13 as a technician writes them, "0x1A02, 0x1A03";
    before, the snapshot's list showed as Python wrote it, "['0x1A02']"."""
    if assigned is None:
        return "-"
    if isinstance(assigned, str):
        return assigned
    return ", ".join(str(i) for i in assigned) or "none"


def ecat_html(snap: Mapping[str, Any]) -> str:
    leds = snap.get("leds") or {}
    rows = [
        *esm_rows(snap),
        ("Drive", esc(snap.get("drive", "-"))),
        ("Slot", esc(snap.get("slot", "-"))),
        ("PDO assignment", esc(f"Rx {pdo_list(snap.get('rx_assign'))} · "
                               f"Tx {pdo_list(snap.get('tx_assign'))}")),
        ("Outputs", esc(snap.get("outputs") or "-")),
        ("Inputs", esc(snap.get("inputs") or "-")),
        # Seed 004 ch. 5: the CoE dictionary is the CANopen one, so ch. 4's bit names.
        ("Error register 0x1001", esc(DRIVE_REGISTER_WORDS.value_text(
            int(snap.get("error_register") or 0)))),
        ("Last emergency", esc(snap.get("last_emergency") or "none"))]
    return kv_table(rows, "fr-slave-state") + led_table(
        [(n, led_colour(n), str(p)) for n, p in leds.items()])


def slave_html(device: str, snap: Mapping[str, Any]) -> str:
    title = (f'<p class="fr-title"><b>{esc(snap.get("box_name") or device)}</b> · '
             f'{esc(device)}</p>')
    kind = snap.get("kind")
    if kind == "trscat":
        return title + trscat_html(snap)
    if kind == "cpx_e_ec":
        return title + cpx_html(snap)
    if kind == "fastcat":
        return title + '<p class="fr-muted">The FastCAT has its own tabs: State, Objects.</p>'
    return title + ecat_html(snap)


@dataclass(frozen=True)
class _Causes:
    """One instructor connection's Slave picker and the causes of the slave it picked."""

    picker: Any
    html: Any


NO_CAUSE = '<p class="fr-muted">no injected cause</p>'


class SlavePanel:
    """The Slave tab. Each page shows the slave it picked (its picker, its click in the 3D
    view): the picker and the tab's HTML are server-level widgets whose value and content go
    to each page for its own pick (app/ui/panels/client_pick.py). Before, one page's pick
    moved every page's tab (docs/dashboard.md "Several browsers")."""

    def __init__(self, server: viser.ViserServer, order: Sequence[str]) -> None:
        self._options = tuple(order) or ("-",)
        self.pick = ClientPick(server, server.gui.add_dropdown("Slave", self._options))
        # The Injected rows and undiagnosed module faults: the instructor's only. With a token
        # they are a folder per instructor connection with a Slave picker of its own: its pick
        # of the slave whose causes to read moves no page's Slave tab (docs/classroom.md). It
        # follows its own page's picks (the Slave picker, a click in the 3D view).
        instructor = instructor_for(server)
        self._shared = instructor.shared
        self._html = ClientHtml(server, server.gui.add_html(""))
        self._causes = None if instructor.shared else instructor.part(self._causes_form)
        self._devices: Mapping[str, Any] = {}
        # A causes table's writers: its pick's callback and the dashboard's frame update.
        # Each reads the pick and the frame and writes under it, or one wrote what it read
        # before the other's write over it, and the table kept that until the next frame.
        self._causes_lock = threading.Lock()
        self.on_pick: Callable[[viser.ClientHandle, str], None] | None = None  # LineView
        self.pick.on_pick(self._picked)

    def _causes_form(self, gui: Any) -> _Causes:
        with gui.add_folder("Slave causes"):
            form = _Causes(gui.add_dropdown("Slave", self._options, initial_value=self.selected,
                                            hint="the slave whose injected causes show"),
                           gui.add_html(NO_CAUSE))
        form.picker.on_update(lambda _event: self._show(form))
        return form

    def _picked(self, client: viser.ClientHandle, device: str) -> None:
        self._follow(client.client_id, device)
        # At once, not at the next frame: 1/30 s away on an idle rig (paused or not), as long
        # as a busy simulation thread takes (a long advance, a catch-up) otherwise.
        self._refresh()
        if self.on_pick is not None:
            self.on_pick(client, device)

    def _follow(self, client_id: int | None, device: str) -> None:
        """The instructor's causes folder of ``client_id`` (every one's when None) follows."""
        if self._causes is None:
            return
        forms = self._causes.each() if client_id is None else \
            [f for f in (self._causes.of(client_id),) if f is not None]
        for form in forms:
            if form.picker.value != device:
                form.picker.value = device

    def _show(self, form: _Causes) -> None:
        with self._causes_lock:
            device = str(form.picker.value)
            html = split_instructor(slave_html(device, as_drawn(self._devices, device)),
                                    "fr-slave-causes")[1] or NO_CAUSE
            if form.html.content != html:
                form.html.content = html

    @property
    def selected(self) -> str:
        """Where a new page starts: the last pick for every page (a scenario's focus)."""
        return self.pick.default

    def selected_for(self, client_id: int | None) -> str:
        """The slave ``client_id``'s page shows."""
        return self.pick.value_for(client_id)

    def select(self, device: str, client: viser.ClientHandle | None = None) -> None:
        """``client``'s page picks ``device`` (its click), every page when None."""
        if device not in self.pick.options:
            return
        if self.pick.pick(device, client):
            self._follow(client.client_id if client is not None else None, device)
        self._refresh()

    def _public(self, device: str) -> str:
        html = slave_html(device, as_drawn(self._devices, device))
        return html if self._shared else split_instructor(html, "fr-slave-causes")[0]

    def _refresh(self) -> None:
        """Each page the HTML of its own pick (the dashboard thread, or a pick's)."""
        shown: dict[str, str] = {}

        def content_for(client_id: int) -> str:
            device = self.selected_for(client_id)
            if device not in shown:
                shown[device] = self._public(device)
            return shown[device]

        self._html.show(content_for)

    def update(self, devices: Mapping[str, Any]) -> None:
        self._devices = devices
        self._refresh()
        if self._causes is not None:
            for form in self._causes.each():
                self._show(form)

    @property
    def content(self) -> str:
        """The HTML of the slave a new page starts at, the instructor's rows included
        (tests)."""
        return slave_html(self.selected, as_drawn(self._devices, self.selected))
