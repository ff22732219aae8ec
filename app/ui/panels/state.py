"""The state panel: what a commissioning engineer reads off the coupler and the master.

ESM state, Fault active (0x5100:1), emergency data (0x5400), AL status and AL status code with
their meaning (seed 000 §7.7; manufacturer codes 0x80XX read by the FastCAT's one decoder,
``devices.fastcat.alarms.decode_al_status``, as the Line and Codes tabs), the latched alarm,
CNF phase and scan progress. Server-level HTML handles, so every browser sees the same text:
the title line (box, station, simulated time) and the table are two handles, each rewritten
only when its own text changes. The time moves ten times a second; the table only when a
value in it does, so a click's answer is not queued behind a stream of identical tables
(benchmarks 2 and 3, docs/performance.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import viser

from app.ui.panels.per_client import RoleHtml, instructor_for
from app.ui.style import badge, clock, esc, kv_table
from devices.ethercat import al_status_name
from devices.fastcat.alarms import TABLE_WORDS, al_status_meaning


def al_code_text(code: int) -> str:
    """The meaning of an AL status code; a FastCAT 0x80XX names the module and the coupler
    code (a module alarm has no AL status code, seed 000 §7.7)."""
    return al_status_meaning(code)


def alarm_text(alarm: Mapping[str, Any] | None) -> str:
    if not alarm:
        return badge("none", "ok")
    where = f", module {alarm['module']}" if alarm.get("module") else ""
    notes = ["resettable" if alarm.get("resettable") else "needs a resync"]
    notes.append("cause present" if alarm.get("cause_present") else "cause gone")
    title = f"0x{int(alarm['code']):02X} {alarm.get('name', '')}"
    table = str(alarm.get("table", ""))
    return (f"{badge(title, 'bad')}"
            # one unit: "coupler" alone fitted the badge's line to the scrollbar's edge
            f' <span class="fr-nowrap">{esc(TABLE_WORDS.get(table, table))}{esc(where)}</span><br>'
            f"{esc(alarm.get('description', ''))}"
            f" <span class=\"fr-muted\">({esc('; '.join(notes))})</span>")


def rotary_text(snap: Mapping[str, Any]) -> str:
    """The switch position, and what the coupler read at power-up when that differs (§6.20)."""
    switch, read = snap.get("rotary_switch", "?"), snap.get("rotary_read")
    text = str(switch)
    if read is not None and read != switch:
        text += f" (0x5302 = {read}, read at power-up)"
    return text + f", address check {'on' if snap.get('address_check') else 'off'}"


def state_rows(snap: Mapping[str, Any]) -> list[tuple[str, str]]:
    esm = str(snap.get("esm", "?"))
    requested = str(snap.get("requested", esm))
    esm_html = badge(esm, "ok" if esm == "OP" else "warn")
    if requested != esm:
        esm_html += f' <span class="fr-muted">requested {esc(requested)}</span>'
    if not snap.get("powered"):
        esm_html = badge("power off", "muted")
    fault = bool(snap.get("fault_active"))
    al_status = int(snap.get("al_status", 0))
    al_code = int(snap.get("al_status_code", 0))
    word = int(snap.get("emergency_data", 0))
    cnf = snap.get("cnf") or {}
    scan = snap.get("scan") or {}
    phase = str(cnf.get("phase", "idle"))
    if cnf.get("pressed"):
        phase = f"pressed {float(cnf.get('held_s', 0.0)):.1f} s"
    if scan.get("active"):
        phase += f", scan {scan.get('done', 0)}/{scan.get('total', 0)}"
    return [
        ("ESM state", esm_html),
        ("Fault active", badge("TRUE", "bad") if fault else badge("FALSE", "ok")),
        ("0x5400", esc(f"0x{word:08X}")),
        ("AL status", esc(f"0x{al_status:04X} {al_status_name(al_status)}")),
        ("AL status code", esc(f"0x{al_code:04X} {al_code_text(al_code)}")),
        ("Alarm", alarm_text(snap.get("alarm"))),
        ("CNF", esc(phase)),
        ("Configuration", config_text(snap)),
        ("Rotary switch", esc(rotary_text(snap))),
        ("Causes", causes_text(snap)),
        ("Injected", injected_text(snap.get("injected") or [])),
    ]


def causes_text(snap: Mapping[str, Any]) -> str:
    """The rail's physical causes as the model words them (snapshot ``causes``, made by
    devices/fastcat/causes.py): an injected cause is the Injected row's. A cause that is not
    the latched alarm's while one is latched says so: §7 signals the first alarm only."""
    alarm = snap.get("alarm")
    waits = "" if not alarm else \
        f" (not signalled: 0x{int(alarm['code']):02X} {alarm['name']} latched first (§7))"
    causes = [str(c.get("text", "")) + ("" if c.get("latched") or c.get("code") is None
                                        else waits)
              for c in snap.get("causes") or [] if not c.get("injected")]
    return esc("; ".join(causes)) if causes else '<span class="fr-muted">none</span>'


def config_text(snap: Mapping[str, Any]) -> str:
    """The rail as a scan would find it now against flash (snapshot ``config``), and a note
    when the rail differs from the last scan: before, flash was compared with the last scan
    only and read "matches flash" with another module on the rail."""
    stored = snap.get("stored_config")
    config = snap.get("config") or {}
    now = [tuple(entry) for entry in config.get("now") or []]
    if stored is None:
        html = badge("none stored", "warn")
    elif config.get("vs_flash") is None:
        html = badge("matches flash", "ok")
    else:
        n = int(config["vs_flash"])
        here = f"{now[n - 1][1]} in slot {now[n - 1][0]}" if n <= len(now) else "none"
        flash = stored[n - 1] if n <= len(stored) else "none"
        html = (f'{badge("differs from flash", "bad")} <span>module {n}: {esc(here)}, '
                f"flash {esc(flash)}</span>")
    if config.get("vs_scan") is not None:  # worded by the model (devices/fastcat/causes.py)
        html += f'<br><span class="fr-muted">{esc(config.get("vs_scan_text", ""))}</span>'
    return html


# Where an injected cause sits, in the words of the device's manual: a FastCAT or CPX-E-EC
# module (and a CPX channel), a TRS-CAT slot, a sync manager.
INJECTED_WHERE = (("module", "module {}"), ("channel", "channel {}"), ("slot", "slot {}"),
                  ("sm", "SM{}"))


def injected_text(injected: Sequence[Mapping[str, Any]]) -> str:
    """The causes an instructor injected: without this row an injected alarm read "cause
    present" next to "Causes: none" (the row of the physical causes). One formatter for every
    device's State / Slave tab: "0x04 MISSING_NODE_ANSWER on module 2" (FastCAT, with its
    code), "CONFIG_ERROR on slot 2", "sm_invalid_size on SM2" (TRS-CAT), "short_circuit on
    module 2 channel 3" (CPX-E-EC)."""
    if not injected:
        return '<span class="fr-muted">none</span>'
    return esc(", ".join(_injected_one(i) for i in injected))


def _injected_one(cause: Mapping[str, Any]) -> str:
    code = f"0x{int(cause['code']):02X} " if cause.get("code") is not None else ""
    where = " ".join(word.format(cause[key]) for key, word in INJECTED_WHERE
                     if cause.get(key) is not None)
    return f"{code}{cause.get('fault', '?')}{' on ' + where if where else ''}"


def title(snap: Mapping[str, Any], master_snap: Mapping[str, Any] | None, t_us: int) -> str:
    """``Box 1 (FastCAT) · station 1001 · t = 12.3 s`` (the master knows the box name)."""
    station = snap.get("station_address")
    names = [s.get("name") for s in (master_snap or {}).get("slaves", [])
             if s.get("station_address") == station]
    name = names[0] if names and names[0] else str(snap.get("id", "FastCAT"))
    # Simulated time in tenths: the text changes 10 times a second at most, and a paused
    # rig shows a fixed value (screenshots).
    return (f'<p class="fr-title"><b>{esc(name)}</b> · station {esc(station)} · '
            f'{clock(t_us // 100_000 / 10)}</p>')


class StatePanel:
    def __init__(self, server: viser.ViserServer) -> None:
        # Two bare <div>s one after the other lay out as the one <div> they replace: the
        # title's bottom margin collapses through its div (no padding, no border), so the
        # screenshots do not move.
        self._title = server.gui.add_html("")
        # The Causes and Injected rows go to the instructor's connections only (RoleHtml).
        self._table = RoleHtml(server, instructor_for(server),
                               kv_table([("ESM state", "-")], "fr-state"), "fr-state-causes")
        self._shown_title = ""

    def update(self, snap: Mapping[str, Any], master_snap: Mapping[str, Any] | None = None,
               t_us: int = 0) -> None:
        heading = title(snap, master_snap, t_us)
        if heading != self._shown_title:
            self._title.content = self._shown_title = heading
        self._table.show(kv_table(state_rows(snap), "fr-state"))
