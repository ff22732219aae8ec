"""The line view's texts, colours and geometry without a browser: headers, LED words, the
expansion and module notes, cable routes, the master panel's table and the focus targets.

Seeds: 003 (master: positions from 0, station addresses, AL status codes), 001 §9.3.2 (TRS-CAT
ASCII idents, 0xF030 / 0xF050), 002 tables 11-13 (CPX-E-EC LED colours), ETG.1300 (pattern
names). The snapshots are built by hand in the master snapshot contract's shape.
"""

from __future__ import annotations

import itertools
import re
from html import unescape
from typing import Any

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.line.bodies import blink_words, header_text, state_tone
from app.ui.line.cables import Cable, cable_label, label_point, pulled_route, pulled_text, route
from app.ui.line.controls import cable_options, slave_options
from app.ui.line.io_bodies import (
    LED_WORDS,
    REASON_WORDS,
    channel_levels,
    channel_list,
    expansion_note,
    ident_text,
    module_error,
    module_note,
)
from app.ui.line.master_panel import (
    dc_text,
    esc_errors_table,
    live_table,
    log_table,
    slaves_table,
    status_table,
)
from app.ui.line.scene import Box, line_order, slave_entries
from app.ui.line.slave_panel import alarm_text, bits, slave_html
from app.ui.line.target_actions import targets
from app.ui.line.view import camera_for, focus_target
from app.ui.panels.per_client import split_instructor
from devices.cpx.leds import MODULE_LED_CAUSES, module_error_led
from devices.cpx.unseen import UNSEEN_REASONS

SLAVE: dict[str, Any] = {
    "position": 1, "device": "trscat", "name": "Box 2 (TRS-CAT)", "station_address": 1002,
    "present": True, "state": "OP", "requested": "OP",
    "al_status": 8, "al_status_code": 0, "al_status_text": "No error", "dc": True,
    "counters": {"lost_frames": 1, "wkc_errors": 2, "emergencies": 3, "state_changes": 4}}


@pytest.mark.parametrize(("change", "tone"), [
    ({}, "ok"),
    ({"state": "SAFEOP", "requested": "SAFEOP"}, "busy"),  # parked below the target OP
    ({"state": "PREOP", "al_status": 0x12, "al_status_code": 0x70}, "bad"),
    ({"state": None, "present": False}, "gone"),
])
def test_state_tone_against_the_master_target(change: dict[str, Any], tone: str) -> None:
    assert state_tone({**SLAVE, **change}, "OP") == tone


@pytest.mark.parametrize(("change", "text"), [
    ({}, "1 · 1002 · OP"),
    ({"state": "PREOP", "al_status_code": 0x70}, "1 · 1002 · PREOP · AL 0x0070"),
    # What the master reads: a lost slave is not seen; why (no link, no supply) is the
    # instructor's injected cause, not the shared scene's.
    ({"state": None, "present": False}, "1 · 1002 · not seen"),
])
def test_header_text(change: dict[str, Any], text: str) -> None:
    assert header_text({**SLAVE, **change}, 1) == text


def test_blink_words_leave_out_what_a_still_shows() -> None:
    leds = [("RUN", "on"), ("ERROR", "double_flash"), ("LINK-ACT IN", "flickering"),
            ("LINK-ACT OUT", "flickering"), ("BUS", "off")]
    assert blink_words(leds) == "ERROR double flash\nLINK-ACT IN, LINK-ACT OUT flickering"
    assert blink_words([("RUN", "on")]) == ""


@pytest.mark.parametrize(("ident", "text"), [
    (0x494F2D45, "IO-E"), ("0x414E2D45", "AN-E"), (0, "-"), (0x01020304, "0x01020304")])
def test_ident_text_reads_the_ascii_idents(ident: int | str, text: str) -> None:
    """Seed 001 §9.3.2: expansion idents are four ASCII characters."""
    assert ident_text(ident) == text


def test_expansion_note() -> None:
    """Seed 001 §9.3.2: sub 0 of 0xF030 / 0xF050 is the count, sub 1 the integrated module
    (IO-B), expansion n is sub n + 1 (the lists the TRS-CAT's snapshot carries)."""
    io_b, io_e, an_e = 0x494F2D42, 0x494F2D45, 0x414E2D45
    snap: dict[str, Any] = {"slots": [{}, {"serviced": True}, {"serviced": True}],
                            "f030": [3, io_b, io_e, an_e, 0], "f050": [3, io_b, io_e, io_e, 0],
                            "alarms": []}
    assert expansion_note(snap, 1) == ""
    assert expansion_note(snap, 2) == "cfg AN-E"  # 0xF030 wants AN-E, 0xF050 found IO-E
    snap["alarms"] = [{"code": "0xA000", "name": "CONFIG_ERROR", "slot": 2}]
    assert expansion_note(snap, 2) == "cfg AN-E\n0xA000"  # what was configured, and the code
    snap["f050"] = snap["f030"]
    assert expansion_note(snap, 2) == "0xA000"
    snap["slots"][1]["serviced"] = False
    assert expansion_note(snap, 1) == "not seen"


def diagnosed(cause: str, *channels: int) -> list[dict[str, Any]]:
    """A module snapshot's "diagnosed" (devices/cpx/diagnosis.py of_module)."""
    return [{"cause": cause, "channel": c} for c in channels] or [
        {"cause": cause, "channel": None}]


def unseen(cause: str, reason: str, *channels: int) -> list[dict[str, Any]]:
    """A module snapshot's "undiagnosed" entry (devices/cpx/unseen.py undiagnosed)."""
    return [{"cause": cause, "channels": list(channels), "reason": reason}]


def modelled(module: dict[str, Any]) -> dict[str, Any]:
    """The hand-built module with the "error_led" the model derives from its "diagnosed"
    (devices/cpx/leds.py module_error_led), as devices/cpx/device.py snapshot adds it."""
    pairs = [(d["cause"], d["channel"]) for d in module.get("diagnosed") or []]
    return {**module, "error_led": module_error_led(pairs)}


@pytest.mark.parametrize(("module", "error", "levels"), [
    ({"short": "16DI", "inputs": [1, 0, 1]}, "", [True, False, True]),
    ({"short": "8DO", "driven": [0, 0, 0, 1], "shorted": [3],
      "diagnosed": diagnosed("short_circuit_outputs", 3)}, "short 3",
     [False, False, False, True]),
    ({"short": "4AI-U-I", "inputs": [5, 0], "wire_broken": [0, 1],
      "diagnosed": diagnosed("wire_break", 0, 1)}, "wire 0,1", []),
    ({"short": "16DI", "inputs": [], "failed": True,
      "diagnosed": diagnosed("module_failure")}, "failed", []),
    ({"short": "16DI", "sensor_supply_short": True,
      "diagnosed": diagnosed("short_circuit_sensor_supply")}, "sensor short", []),
    # docs/cpx-e-ec.md choice 30: wired, but the output is off: the module sees nothing
    ({"short": "8DO", "driven": [0] * 8, "shorted": [3], "diagnosed": [],
      "undiagnosed": unseen("short_circuit_outputs", "output_off", 3)}, "", [False] * 8),
    ({"short": "4AI-U-I", "inputs": [0] * 4, "wire_broken": [0], "diagnosed": []}, "", []),
])
def test_cpx_module_led_and_channels(module: dict[str, Any], error: str,
                                     levels: list[bool]) -> None:
    assert module_error(modelled(module)) == error
    assert channel_levels(module) == levels


def test_every_reason_the_model_gives_has_an_entry() -> None:
    """The model says why a wired cause is not diagnosed (devices/cpx/unseen.py); the Slave
    tab has an entry for each reason and for nothing else (one without would show its id)."""
    assert set(REASON_WORDS) == set(UNSEEN_REASONS)


def test_every_cause_the_model_shows_has_plate_words() -> None:
    """The model names the cause a module's red LED shows (devices/cpx/leds.py); the plate has
    words for each one and for nothing else (a cause without words would show its id)."""
    assert set(LED_WORDS) == set(MODULE_LED_CAUSES)


@pytest.mark.parametrize(("channels", "text"), [
    ([3], "3"), ([0, 1], "0,1"), ([0, 1, 2, 3], "0-3"), ([5, 0, 1, 2, 3], "0-3,5"),
    ([0, 1, 3, 4, 6, 7], "0,1,3,4,6,7"), (list(range(8)), "0-7"),
])
def test_channel_lists_shorten_runs(channels: list[int], text: str) -> None:
    assert channel_list(channels) == text


@pytest.mark.parametrize(("module", "note"), [
    ({"diagnosed": diagnosed("short_circuit_outputs", 3)}, "short 3"),  # one line if it fits
    ({"diagnosed": diagnosed("wire_break", 0, 1)}, "wire\n0,1"),
    ({"diagnosed": diagnosed("short_circuit_outputs", *range(8))}, "short\n0-7"),
    # too long for a line: the count
    ({"diagnosed": diagnosed("short_circuit_outputs", 0, 1, 3, 4, 6, 7)}, "short\n6 ch."),
    ({"diagnosed": diagnosed("short_circuit_sensor_supply")}, "sensor\nshort"),
    ({"diagnosed": diagnosed("module_failure"), "shorted": [1]}, "failed"),
    ({"shorted": [3], "diagnosed": [],
      "undiagnosed": unseen("short_circuit_outputs", "output_off", 3)}, ""),  # no note
    ({}, ""),
])
def test_module_note_takes_two_lines_at_most(module: dict[str, Any], note: str) -> None:
    assert module_note(modelled(module)) == note
    assert all(len(line) <= 7 for line in note.split("\n"))


def test_cable_routes() -> None:
    assert route((1.0, -1.6), (3.0, -1.6), -3.5) == [(1.0, -1.6), (3.0, -1.6)]
    wrap = route((9.6, -1.6), (-3.0, -8.2), -3.5)  # end of row 1 to the start of row 2
    assert wrap[0] == (9.6, -1.6) and wrap[-1] == (-3.0, -8.2)
    assert all(a[0] == b[0] or a[1] == b[1] for a, b in itertools.pairwise(wrap))
    assert min(z for _x, z in wrap) == -8.2 and (9.95, -3.5) in wrap
    pulled = pulled_route([(0.0, 0.0), (2.0, 0.0)])
    assert pulled[-2] == (0.9, 0.0) and pulled[-1][1] < 0  # stops short, the end hangs
    assert label_point(wrap) == ((9.95 - 3.35) / 2, -3.5)



@pytest.mark.parametrize(("cable", "text"), [
    ({"plugged": True, "master_pulled": False, "pulled_at": []}, ""),
    ({"plugged": False}, "pulled"),  # a snapshot without the ends: the master's own pull
    ({"plugged": False, "master_pulled": True, "pulled_at": []}, "pulled"),
    ({"plugged": False, "master_pulled": False, "pulled_at": ["trscat OUT"]},
     "pulled at trscat OUT"),
    ({"plugged": False, "master_pulled": False, "pulled_at": ["trscat OUT", "cpx IN"]},
     "pulled at trscat OUT and cpx IN"),
    ({"plugged": False, "master_pulled": True, "pulled_at": ["cpx IN"]},
     "pulled, also at cpx IN"),
])
def test_pulled_text_says_which_end_is_out(cable: dict[str, Any], text: str) -> None:
    """docs/ethercat-master.md: a cable is plugged only when both its ends are; the snapshot
    names the ends a slave's own plug has out (``pulled_at``) apart from the master's pull."""
    assert pulled_text(cable) == text


def test_a_cable_s_label_says_pulled_whichever_end_is_out() -> None:
    short, long = [(0.0, 0.0), (1.0, 0.0)], [(0.0, 0.0), (4.0, 0.0)]
    assert cable_label(2, True, short) == "cable 2"
    assert cable_label(2, False, short) == "cable 2\npulled"
    assert cable_label(2, False, long) == "cable 2 pulled"


class _Node:
    def __init__(self, text: str = "") -> None:
        self.text, self.clicked = text, None

    def on_click(self, handler: Any) -> None:
        self.clicked = handler

    def remove(self) -> None:
        pass


class _Scene:
    def __init__(self) -> None:
        self.boxes: list[_Node] = []
        self.labels: list[_Node] = []

    def add_box(self, name: str, **_kw: Any) -> _Node:
        self.boxes.append(_Node())
        return self.boxes[-1]

    def add_label(self, name: str, text: str, **_kw: Any) -> _Node:
        self.labels.append(_Node(text))
        return self.labels[-1]


@pytest.mark.parametrize(("cable", "colour_plugged", "verb_plugged"), [
    ({"plugged": True, "master_pulled": False, "pulled_at": []}, True, True),
    ({"plugged": False, "master_pulled": True, "pulled_at": []}, False, False),
    # Out at the CPX-E-EC's own IN: drawn pulled, the click still pulls the master's cable
    ({"plugged": False, "master_pulled": False, "pulled_at": ["cpx IN"]}, False, True),
    ({"plugged": False, "master_pulled": True, "pulled_at": ["cpx IN"]}, False, False),
])
def test_a_cable_is_drawn_as_the_snapshot_says_and_clicks_the_master_s_cable(
        cable: dict[str, Any], colour_plugged: bool, verb_plugged: bool) -> None:
    """The 3D cable shows the cable's real state (both ends); a click moves the master's
    ``cables`` as before (pull when the master has it in, plug when it has it out)."""
    scene, clicks = _Scene(), []
    server: Any = type("Server", (), {"scene": scene})()
    drawn = Cable(server, 2, [(0.0, 0.0), (1.0, 0.0)],
                  lambda client, index, plugged: clicks.append((index, plugged)))
    drawn.show(cable)
    assert drawn.plugged is colour_plugged
    assert drawn.label_text == cable_label(2, colour_plugged, drawn.points)
    assert scene.boxes[0].clicked is not None
    scene.boxes[0].clicked(type("Event", (), {"client": None})())
    assert clicks == [(2, verb_plugged)]


def test_a_cable_pulled_at_its_out_end_hangs_there() -> None:
    points = [(0.0, 0.0), (2.0, 0.0)]
    at_out = pulled_route(points, at_start=True)
    assert at_out[-1] == (2.0, 0.0)  # the IN end stays in its port
    assert at_out[1] == (1.1, 0.0)  # the OUT end stops short and hangs, toward the OUT port
    assert at_out[0][1] < 0 and at_out[0][0] < 1.1


MASTER: dict[str, Any] = {
    "target": "OP", "slaves": [
        {**SLAVE, "position": 0, "device": "fastcat", "station_address": 1001},
        {**SLAVE}, {**SLAVE, "position": 2, "device": "cpx", "station_address": 1003,
                    "state": None, "present": False}],
    "cables": [{"index": 0, "from": "master", "to": "fastcat", "plugged": True},
               {"index": 1, "from": "fastcat", "to": "trscat", "plugged": True},
               {"index": 2, "from": "trscat", "to": "cpx", "plugged": False}]}


def test_line_order_by_device_or_by_station_address() -> None:
    assert line_order(MASTER, {}) == ["fastcat", "trscat", "cpx"]
    old = {"slaves": [{"station_address": 1002}, {"station_address": 1001}]}
    devices = {"a": {"kind": "fastcat", "station_address": 1001},
               "b": {"kind": "trscat", "station_address": 1002}}
    assert line_order(old, devices) == ["b", "a"]
    assert slave_entries(MASTER, ["fastcat", "trscat", "cpx"])["cpx"]["position"] == 2


def test_master_panel_table_and_controls() -> None:
    html = slaves_table(MASTER["slaves"], "OP")
    assert html.count("<tr>") == 4  # header + 3 slaves
    assert "Box 2 (TRS-CAT)" in html and "not seen" in html
    assert "1/<wbr>2/<wbr>3/<wbr>4" in html  # may wrap after a slash, never in a number
    assert cable_options(MASTER, []) == ["0 master -> fastcat", "1 fastcat -> trscat",
                                         "2 trscat -> cpx (pulled)"]
    assert cable_options({}, ["fastcat", "trscat"]) == ["0 master -> fastcat",
                                                       "1 fastcat -> trscat"]
    off = {"slaves": [SLAVE], "injected": {"powered": [False]}}
    assert slave_options(off, ["trscat"]) == ["0 trscat (off)"]
    assert "NOT_SYNCHRONIZED" in dc_text({"state": "NOT_SYNCHRONIZED"})
    log = log_table([{"timestamp": "12/11/2019 14.51.30 421 ms", "text": "first"},
                     {"t": 1.5, "text": "second <b>"}])
    assert log.index("second &lt;b&gt;") < log.index("first")  # newest first, escaped
    assert "1.500 s" in log


def test_the_master_panel_says_which_cable_is_out_and_at_which_end() -> None:
    """The Line tab, instructor's rows: a cable out at a slave's own plug is named with that
    end, as the snapshot's ``pulled_at`` says; no row while every cable is in. A trainee's
    browser gets the table without it (a real master sees no cable)."""
    assert "Injected" not in status_table({"cables": MASTER["cables"][:2]})
    own = {"cables": [*MASTER["cables"][:2],
                      {"index": 2, "from": "trscat", "to": "cpx", "plugged": False,
                       "master_pulled": False, "pulled_at": ["trscat OUT"]}]}
    public, instructor = split_instructor(status_table(own), "causes")
    assert "<th>Injected</th>" in instructor
    assert "2 trscat -&gt; cpx pulled at trscat OUT" in instructor and "pulled" not in public
    assert "2 trscat -&gt; cpx pulled<" in status_table(MASTER)  # the master's own pull


def test_the_cable_list_says_where_a_cable_is_out() -> None:
    """The Line controls' Cable list (Pull / Plug move the master's cable): a cable out at a
    slave's own plug reads pulled there, from the master's snapshot of a real line."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.advance(10)
    rig.apply("trscat", "link", {"connected": False, "port": "out"})
    rig.apply("master", "pull_cable", {"cable": 3})
    rig.apply("drive_ec-ecat", "link", {"connected": False})
    master = rig.snapshot()["devices"]["master"]
    assert cable_options(master, []) == [
        "0 master -> fastcat", "1 fastcat -> trscat", "2 trscat -> cpx (pulled at trscat OUT)",
        "3 cpx -> drive_ec-ecat (pulled, also at drive_ec-ecat IN)"]


def test_esc_error_counters_per_slave_and_port_and_the_damaged_cable() -> None:
    """docs/ethercat-master.md "Damaged cable": cable 2 spoils frames; the CPX-E-EC behind it
    counts them invalid on port 0 (IN), the TRS-CAT before it forwarded on port 1 (OUT)."""
    quiet = {"invalid": [0, 0], "rx": [0, 0], "forwarded": [0, 0], "lost_link": [0, 0],
             "epu": 0}
    slaves = [{**SLAVE, "position": 1, "name": "Box 2 (TRS-CAT)",
               "esc_errors": {**quiet, "forwarded": [0, 12]}},
              {**SLAVE, "position": 2, "name": "Box 3 (CPX-E-EC)",
               "esc_errors": {**quiet, "invalid": [12, 0], "epu": 12, "lost_link": [1, 0]}},
              {**SLAVE, "position": 3, "name": "Box 4"}]  # a master without the counters
    html = esc_errors_table(slaves)
    rows = html.split("<tr>")[2:]
    assert len(rows) == 3
    assert "0/<wbr>0/<wbr>0" in rows[0] and "0/<wbr>12/<wbr>0" in rows[0]
    assert '<span class="fr-line-bad">12/<wbr>0/<wbr>1</span>' in rows[1]
    assert rows[1].count("12") == 2  # port 0's invalid and the processing unit
    assert rows[2].count("-") >= 3
    assert "invalid frames (0x0300) / forwarded (0x0308) / lost links (0x0310)" in html
    master = {"cables": [{"index": 2, "from": "trscat", "to": "cpx", "plugged": True,
                          "damaged": 20}]}
    assert cable_options(master, []) == ["2 trscat -> cpx (damaged 20 %)"]


def test_targets_and_focus_names() -> None:
    trscat = {"slots": [{"slot": 0}, {"slot": 1}, {"slot": 2}]}
    assert targets("trscat", trscat) == ["trscat", "trscat/1", "trscat/2"]
    assert targets("cpx", {"modules": [{"module": 1}, {"module": 2}]}) == [
        "cpx", "cpx/1", "cpx/2"]
    assert [focus_target(t) for t in ("trscat", "cpx:2", "fastcat/3")] == [
        "trscat", "cpx", "fastcat"]


def test_camera_frames_the_box_and_looks_from_above() -> None:
    position, look_at = camera_for(Box(-3.0, 11.0, -10.0, 3.0), 0.84)
    assert look_at == (4.0, 0.0, -3.5)
    assert position[0] == 4.0 and position[1] < -10 and position[2] > look_at[2]
    near, _ = camera_for(Box(0.0, 9.0, -2.0, 2.0), 0.84)
    assert near[1] > position[1]  # a smaller box: the camera comes closer


def test_slave_panel_texts() -> None:
    assert bits([1, 0, 1, 1]) == "1011" and bits([0.5, 2.0]) == "0.5 2"
    # by 8, so that a narrow cell wraps between groups, not inside 16 digits (22_cpx_form.png)
    assert bits([1] + [0] * 15) == "10000000 00000000" and bits([0] * 8) == "00000000"
    assert alarm_text({"code": "0xA000", "name": "CONFIG_ERROR", "slot": 2}) == (
        "0xA000 CONFIG_ERROR (slot 2)")
    html = slave_html("trscat", {"kind": "trscat", "esm": "PREOP", "requested": "SAFEOP",
                                 "al_status": 0x12, "al_status_code": 0x70,
                                 "leds": {"ERROR": "blinking"}, "slots": [
                                     {"slot": 0, "type": "TRS-CAT integrated",
                                      "ident": "0x494F2D42", "inputs": [1, 0]}]})
    assert "0x0012 PREOP + error" in html and "0x0070" in html and "IO-B" in html
    assert "blinking" in html
    cpx = slave_html("cpx", {"kind": "cpx_e_ec", "esm": "OP", "modules": [modelled(
        {"module": 2, "short": "8DO", "outputs": [0, 0, 0, 1], "shorted": [3],
         "diagnosed": diagnosed("short_circuit_outputs", 3)})],
        "history": {"messages": [{"sub": 7, "type": "error", "text_id": "0x3702",
                                  "text": "Short circuit/overload"}]}})
    assert "short 3" in cpx and "Short circuit/overload" in cpx and "0x3702" in cpx


def _shown(html: str, trainee: bool) -> str:
    """The text of a Slave tab's page: the instructor's whole; a trainee's what a classroom
    sends every browser, the instructor's rows and spans taken out (split_instructor,
    docs/classroom.md)."""
    if trainee:
        html = split_instructor(html, "fr-slave-causes")[0]
    return unescape(re.sub(r"<[^>]+>", "", html))


def _fault_cell(html: str) -> str:
    return re.findall(r'<td class="fr-line-bad">(.*?)</td>', html)[0]


@pytest.mark.parametrize(("module", "fault", "seen"), [
    ({"short": "8DO", "shorted": [3], "diagnosed": [],
      "undiagnosed": unseen("short_circuit_outputs", "output_off", 3)},
     "short 3 (output off: not diagnosed)", ""),
    ({"short": "4AO-U-I", "shorted": [2], "diagnosed": [],
      "undiagnosed": unseen("short_circuit_outputs", "current_range", 2)},
     "short 2 (current range: not diagnosed)", ""),
    ({"short": "8DO", "shorted": [1, 3], "diagnosed": diagnosed("short_circuit_outputs", 1),
      "undiagnosed": unseen("short_circuit_outputs", "output_off", 3)},
     "short 1; short 3 (output off: not diagnosed)", "short 1"),
    ({"short": "8DO", "shorted": [3], "diagnosed": [],
      "undiagnosed": unseen("short_circuit_outputs", "monitor_off", 3)},
     "short 3 (0x2400 monitor off: not diagnosed)", ""),
    ({"short": "8DO", "shorted": [1, 3], "diagnosed": [],
      "undiagnosed": [*unseen("short_circuit_outputs", "output_off", 3),
                      *unseen("short_circuit_outputs", "monitor_off", 1)]},
     "short 3 (output off: not diagnosed); short 1 (0x2400 monitor off: not diagnosed)", ""),
    ({"short": "4AI-U-I", "wire_broken": [0], "diagnosed": [],
      "undiagnosed": unseen("wire_break", "signal_range", 0)},
     "wire 0 (signal range: not diagnosed)", ""),
    ({"short": "16DI", "sensor_supply_short": True, "diagnosed": [],
      "undiagnosed": unseen("short_circuit_sensor_supply", "monitor_off")},
     "sensor short (0x2400 monitor off: not diagnosed)", ""),
    ({"short": "16DI", "failed": True, "diagnosed": [],
      "undiagnosed": unseen("module_failure", "no_application")},
     "failed (bus module not running: not diagnosed)", ""),
    # U_OUT missing: the output is not energised, its short draws no current (choice 30)
    ({"short": "8DO", "shorted": [3], "diagnosed": diagnosed("undervoltage_out"),
      "undiagnosed": unseen("short_circuit_outputs", "no_load_supply", 3)},
     "U_OUT low; short 3 (no load supply: not diagnosed)", "U_OUT low"),
    ({"short": "4AI-U-I", "wire_broken": [0, 1], "diagnosed": diagnosed("wire_break", 0),
      "undiagnosed": unseen("wire_break", "pending", 1)},
     "wire 0; wire 1 (next cycle: not diagnosed)", "wire 0"),
    # the wiring alone says nothing: what is not diagnosed, and why, is the model's
    ({"short": "8DO", "shorted": [3], "diagnosed": [], "undiagnosed": []}, "", ""),
])
def test_cpx_slave_tab_says_what_is_wired_but_not_diagnosed(module: dict[str, Any],
                                                            fault: str, seen: str) -> None:
    """The review (23_cpx_short.png): the 8DO's output 3 shorted while off showed a red LED
    and "short 3" with SF off, 0x1001 = 0 and no 0x10F3 message. The red LED follows the
    diagnosis now; the Slave tab still names the wiring, and why the module does not see
    it (docs/cpx-e-ec.md choice 30), to the instructor only: a cause the device does not
    report is the injected one, which no trainee's page names (docs/classroom.md). What the
    device diagnoses stays for everyone."""
    html = slave_html("cpx", {"kind": "cpx_e_ec", "esm": "OP",
                              "modules": [modelled({"module": 2, **module})]})
    cell = _fault_cell(html)
    assert _shown(cell, trainee=False) == fault
    assert _shown(cell, trainee=True) == seen
    assert "&lt;" not in cell and "&amp;" not in cell  # escaped once, not twice


def test_cpx_slave_tab_hides_an_injected_short_from_a_trainee() -> None:
    """The reviewer's reproducer (rv3/cpx_leak.py): cpx/2 inject_fault short_circuit on
    channel 3 of the 8DO, output off: the device reports nothing (no diagnosis, 0x1001 = 0,
    the Injected row "none"), yet the Fault cell named the short on every page."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.run_until(3_000_000)
    rig.apply("cpx/2", "inject_fault", {"fault": "short_circuit", "channel": 3})
    rig.run_until(4_000_000)
    snap = rig.snapshot()["devices"]["cpx"]
    assert snap["modules"][1]["shorted"] == [3] and not snap["modules"][1]["diagnosed"]
    html = slave_html("cpx", snap)
    assert "short 3 (output off: not diagnosed)" in _shown(html, trainee=False)
    assert "short 3" not in _shown(html, trainee=True)
    assert "diagnosed" not in _shown(html, trainee=True)


def test_cpx_u_out_undervoltage_lights_the_output_modules_red_led() -> None:
    """Seed 002 Tab. 21-24: U_OUT too low is a diagnosis of a module (0x3320, 0x1001 bit 2
    "Сбой напряжения нагрузки на модуле выходов", status bit 4 with the module type, byte 4
    the module's number); the bus module diagnoses it on each module with outputs (error 8,
    docs/cpx-e-ec.md "Physical cause -> codes"), and a module's red LED shows what is
    diagnosed on it (choice 30). The 8DO and the 4AO light it; the input modules do not."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.run_until(3_000_000)
    rig.apply("cpx", "supply", {"out": 15.0})
    rig.run_until(4_000_000)
    modules = rig.snapshot()["devices"]["cpx"]["modules"]
    assert [[d["cause"] for d in m["diagnosed"]] for m in modules] == [
        [], ["undervoltage_out"], [], ["undervoltage_out"]]
    assert [module_error(m) for m in modules] == ["", "U_OUT low", "", "U_OUT low"]
    assert module_note(modules[1]) == "U_OUT\nlow"


@pytest.mark.parametrize(("device", "fault", "during", "after"), [
    ("trscat", "0x3220", "Field supply0.0 V alarm", "Field supply24.0 V ok"),
    ("cpx", "undervoltage_out", "U_OUT 17.0 V", "U_OUT 24.0 V"),
    ("cpx", "undervoltage_el_sen", "U_EL/SEN 17.0 V", "U_EL/SEN 24.0 V"),
])
def test_an_injected_supply_fault_reads_on_the_trainee_s_slave_tab(
        device: str, fault: str, during: str, after: str) -> None:
    """The walkthrough: with 0x3220 injected on the TRS-CAT's base the trainee's Slave tab
    read "Field supply 24.0 V" beside the alarm badge and the +24V LED off (seed 001 §8.4).
    An injected supply fault is the supply failing: the tab gives what a meter on the
    terminals reads (docs/trscat.md, docs/cpx-e-ec.md choice 27), and the set value again
    once it is cleared."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.run_until(3_000_000)
    rig.apply(device, "inject_fault", {"fault": fault})
    rig.run_until(3_100_000)
    assert during in _shown(slave_html(device, rig.snapshot()["devices"][device]), trainee=True)
    rig.apply(device, "clear_fault", {"fault": fault})
    rig.run_until(3_200_000)
    assert after in _shown(slave_html(device, rig.snapshot()["devices"][device]), trainee=True)


def test_u8_diag_status_and_units_that_do_not_wrap_alone() -> None:
    """The review: "0xF100 diag status 0x0007" printed a U8 (seed 001 §9.3.4) with 4 hex
    digits, and "cycle 1000 µs" wrapped with "µs" alone on the next line."""
    html = slave_html("trscat", {"kind": "trscat", "esm": "OP", "diag_status": 7})
    assert "0x07<" in html and "0x0007" not in html
    live = live_table({"stats": {"frames": 12, "lost_frames": 0, "cycle_us": 1000},
                       "dc": {"state": "COMPENSATING", "deviation_ns": 35, "window_ns": 1000}})
    assert "cycle 1000\u00a0µs" in live
    assert "deviation 35\u00a0ns / window 1000\u00a0ns" in live
