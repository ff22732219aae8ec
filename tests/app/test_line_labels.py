"""The EtherCAT line scene's labels stay apart at the dashboard's default camera (app/ui/line).

Label boxes are estimated as tests/app/label_boxes.py says (viser's screen labels keep their
size on screen; the default camera frames the whole line and the axes under it, the widest
view, so every focus or zoom only widens the gaps). The line is the default rig's, built by
the dashboard as a browser gets it and booted to OP; the tests then show it the texts a
trainee meets at their longest:

- every cable pulled ("cable i pulled", seed 003: the slaves behind it "not seen"),
  also at the slaves' own plugs ("pulled at trscat OUT", docs/ethercat-master.md);
- every DC state of seed 003 (devices/master/dc.py DcState: WAITING_START_TIME and
  NOT_SYNCHRONIZED are the longest) on the master's screen;
- the CPX-E modules with the longest names side by side (seed 002 §2.3.2: 4AI-U-I, 4AO-U-I;
  the default rig has them as modules 3 and 4);
- AL status codes in the headers (seed 000 §7.7) and LEDs blinking in every pattern;
- the drive in alarm, its number under its ESM state (seed 004 ch. 5 "Codici allarmi
  specifici": the display shows it).

What each label shows is the scene's own (texts from the snapshot); these tests only check
that no label covers another label or an LED, and that the texts which belong inside a part
(the master's screen, a module plate, the drive's front) stay inside it.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import pytest
import viser
from label_boxes import TOUCH_PX, Box, label_box, overlaps, px_per_unit

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.line.bodies import wrap
from app.ui.line.io_bodies import TYPE_LINE, short_type
from app.ui.line.scene import LineScene
from devices.cpx.catalog import IO_MODULES
from devices.cpx.leds import module_error_led
from devices.master.dc import DcState
from devices.trscat.catalog import EXPANSIONS

GAP_PX = 3.0  # between two labels on one line (a space at the smallest label size)
BOOT_STEPS = 8000  # 8 s of 1 ms steps: the FastCAT scan and every slave INIT -> OP
Snapshot = dict[str, Any]


@dataclass
class Line:
    server: viser.ViserServer
    scene: LineScene
    camera: Any
    snapshot: Snapshot  # the booted rig's, every device in OP
    t_us: int


@pytest.fixture(scope="module")
def line() -> Iterator[Line]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    runtime = Runtime(rig)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        dashboard = Dashboard(server, runtime)
        dashboard.tick()  # rails, axes and line as the first frame draws them
        assert dashboard.line is not None
        frame = runtime.frame
        yield Line(server, dashboard.line.scene, server.initial_camera,
                   copy.deepcopy(frame.snapshot), frame.t_us)
    finally:
        server.stop()


# ---- the worst texts ------------------------------------------------------------------------
def devices(snap: Snapshot) -> dict[str, Any]:
    return snap["devices"]


def cables_pulled(*pulled: int) -> Callable[[Snapshot], None]:
    """Seed 003: the slaves behind a pulled cable are not seen; the master
    without its own cable waits for a link. The drive, cut off, drops to SAFEOP by itself."""
    def apply(snap: Snapshot) -> None:
        master = devices(snap)["master"]
        for cable in master["cables"]:
            cable["plugged"] = cable["index"] not in pulled
        for slave in master["slaves"][min(pulled):]:
            slave.update(present=False, state=None, al_status=0, al_status_code=0)
        if 0 in pulled:
            master.update(link=False, phase="waiting_link")
        devices(snap)["drive_ec-ecat"]["esm"] = "SAFEOP"
    return apply


def plugs_out(ends: str, master_too: bool = False) -> Callable[[Snapshot], None]:
    """Every cable out at a slave's own plug (``ends``: "in", "out" or "both"; cable 0 has no
    OUT end of a slave), optionally pulled by the master too: the cable labels at their
    longest ("cable 2 / pulled, also / at trscat OUT and cpx IN")."""
    def apply(snap: Snapshot) -> None:
        cables_pulled(0, 1, 2, 3)(snap)
        for cable in devices(snap)["master"]["cables"]:
            at = [f"{cable['from']} OUT"] if ends != "in" and cable["index"] else []
            at += [f"{cable['to']} IN"] if ends != "out" or not cable["index"] else []
            cable.update(master_pulled=master_too, pulled_at=at)
    return apply


def al_codes_and_power(snap: Snapshot) -> None:
    """Headers at their longest: a state with its AL status code (seed 000 §7.7), and a slave
    the master lost."""
    master = devices(snap)["master"]
    master["phase"] = "init_commands"
    for slave in master["slaves"]:
        slave.update(state="PREOP", requested="SAFEOP", al_status=0x12, al_status_code=0x0070)
    master["slaves"][-1].update(state=None, present=False, al_status_code=0)


def no_slave_answers(snap: Snapshot) -> None:
    """Seed 003: link detected, the master sends its frames, and not one slave answers (every
    drive on another fieldbus, say): the phase the master's screen names."""
    master = devices(snap)["master"]
    master["phase"] = "no_answer"
    for slave in master["slaves"]:
        slave.update(present=False, state=None, al_status=0, al_status_code=0)


def blinking(snap: Snapshot) -> None:
    """LED words on four lines (every pattern a still cannot show, Run / Error orange)."""
    trs = devices(snap)["trscat"]["leds"]
    trs.update({"RUN": "blinking", "ERROR": "single_flash", "LINK-ACT IN": "flickering",
                "LINK-ACT OUT": "flickering", "BUS": "double_flash"})
    cpx = devices(snap)["cpx"]["led_states"]
    cpx.update({"Run": {"pattern": "single_flash", "colour": "orange"},
                "Error": {"pattern": "blinking", "colour": "orange"},
                "SF": {"pattern": "double_flash", "colour": "red"}})
    devices(snap)["drive_ec"]["leds"].update(Status="single_flash", Error="double_flash")


def diagnose(module: dict[str, Any], cause: str, *channels: int | None) -> None:
    """What the CPX-E-EC diagnoses on a module (its snapshot's "diagnosed") and the red LED
    the model derives from it ("error_led"): the LED and the note follow the diagnosis, not
    the wiring (docs/cpx-e-ec.md choice 30)."""
    module["diagnosed"] = [{"cause": cause, "channel": c} for c in channels]
    module["error_led"] = module_error_led([(cause, c) for c in channels])


def expansion_and_module_faults(snap: Snapshot) -> None:
    """Seed 001 §9.3.7: an application error on expansion 2, another type found there; seed
    002 §2.5: a short circuit on the 8DO's channel 3 (the line_cpx_short screenshot)."""
    trs = devices(snap)["trscat"]
    trs["alarms"] = [{"code": "0xA000", "slot": 2}]
    trs["f050"][3] = 0x494F2D45  # §9.3.2: IO-E found where AN-E is configured: two lines
    modules = devices(snap)["cpx"]["modules"]
    modules[1]["shorted"] = [3]
    diagnose(modules[1], "short_circuit_outputs", 3)


def every_module_faulted(snap: Snapshot) -> None:
    """Seed 002 §2.5: every CPX-E module with its red LED on and its note at its longest (a
    sensor-supply short, six of the 8DO's outputs shorted, wires broken), side by side, with
    the blink words under the CPX (SF flashing)."""
    modules = devices(snap)["cpx"]["modules"]
    diagnose(modules[0], "short_circuit_sensor_supply", None)
    diagnose(modules[1], "short_circuit_outputs", 0, 1, 3, 4, 6, 7)
    diagnose(modules[2], "wire_break", 0, 2)
    diagnose(modules[3], "wire_break", 0, 1, 2, 3)
    devices(snap)["cpx"]["led_states"]["SF"] = {"pattern": "triple_flash", "colour": "red"}


def dc_state(state: DcState) -> Callable[[Snapshot], None]:
    def apply(snap: Snapshot) -> None:
        devices(snap)["master"]["dc"].update(state=state.value, fault="drift")
    return apply


def lost_and_held(snap: Snapshot) -> None:
    """"running" with its note at its longest: slaves lost and not found, DC slaves held in
    SAFEOP (seed 003 NOT_SYNCHRONIZED; docs/ethercat-master.md "Start-up")."""
    cables_pulled(2)(snap)
    dc_state(DcState.NOT_SYNCHRONIZED)(snap)
    devices(snap)["master"].update(phase="running",
                                   phase_note="1 slave lost, 1 slave not found, 1 DC slave "
                                              "held in SAFEOP",
                                   phase_note_short="2 lost, 1 held")


def drive_alarm(snap: Snapshot) -> None:
    """Alarm 34 latched (seed 004 ch. 5: a two-digit number, as the display shows it), the
    drive's CoE side in SAFEOP after the SM watchdog (the widest ESM word) with its Error LED
    double flashing (the legend under the body)."""
    drive = devices(snap)["drive_ec"]
    drive["alarm"] = {"code": 34, "name": "SYNC_TIMEOUT", "description": "", "effect": ""}
    drive["leds"].update(Status="single_flash", Error="double_flash")
    devices(snap)["drive_ec-ecat"]["esm"] = "SAFEOP"


STATES: dict[str, Callable[[Snapshot], None]] = {
    "running": lambda snap: None,
    "every_cable_pulled": cables_pulled(0, 1, 2, 3),
    **{f"cable_{i}_pulled": cables_pulled(i) for i in range(4)},
    **{f"every_cable_pulled_at_{e}": plugs_out(e) for e in ("in", "out", "both")},
    "every_cable_pulled_everywhere": plugs_out("both", master_too=True),
    "al_codes_and_power": al_codes_and_power,
    "no_slave_answers": no_slave_answers,
    "lost_and_held": lost_and_held,
    "blinking": blinking,
    "drive_alarm": drive_alarm,
    "faults": expansion_and_module_faults,
    "every_module_faulted": every_module_faulted,
    **{f"dc_{s.name}": dc_state(s) for s in DcState},
}


def show(line: Line, state: str) -> None:
    snap = copy.deepcopy(line.snapshot)
    STATES[state](snap)
    line.scene.update(snap, line.t_us)


# ---- boxes ----------------------------------------------------------------------------------
def nodes(line: Line) -> dict[str, Any]:
    # viser lists no scene nodes publicly; the server's registry is what browsers are sent.
    return dict(line.server.scene._handle_from_node_name)


def px_at(line: Line, position: Any) -> float:
    return px_per_unit(line.camera, [float(v) for v in position])


def label_boxes(line: Line) -> dict[str, Box]:
    """Every label a browser draws, by node name (an empty one draws a speck: left out)."""
    return {name: label_box(h, px_at(line, h.position)) for name, h in nodes(line).items()
            if isinstance(h, viser.LabelHandle) and h.visible and str(h.text)}


def solid_box(name: str, handle: viser.BoxHandle) -> Box:
    (x, _, z), (w, _, h) = handle.position, handle.dimensions
    return Box(name, x - w / 2, x + w / 2, z - h / 2, z + h / 2)


def led_boxes(line: Line) -> dict[str, Box]:
    return {name: solid_box(name, h) for name, h in nodes(line).items()
            if isinstance(h, viser.BoxHandle) and "/led_" in name}


def tolerance(line: Line) -> float:
    return TOUCH_PX / px_at(line, line.camera.look_at)


# ---- tests ----------------------------------------------------------------------------------
def side_by_side(boxes: list[Box], tol: float, gap: float) -> list[tuple[str, str]]:
    """Labels on one line (their heights overlap) less than ``gap`` apart: read as one
    word ("4AI-U-I4AO-U-I", "cable 3ESM SAFEOP")."""
    return [(a.text, b.text) for i, a in enumerate(boxes) for b in boxes[i + 1:]
            if min(a.z1, b.z1) - max(a.z0, b.z0) > tol
            and min(a.x1, b.x1) - max(a.x0, b.x0) > -gap]


@pytest.mark.parametrize("state", list(STATES))
def test_no_label_covers_another(line: Line, state: str) -> None:
    show(line, state)
    boxes = list(label_boxes(line).values())
    assert overlaps(boxes, tolerance(line)) == []
    assert side_by_side(boxes, tolerance(line), GAP_PX * tolerance(line)) == []


@pytest.mark.parametrize("state", list(STATES))
def test_no_label_covers_an_led(line: Line, state: str) -> None:
    show(line, state)
    tol = tolerance(line)
    leds = led_boxes(line)
    assert any(name.startswith("/line/") for name in leds)
    # The line's labels over any LED, any label over the line's LEDs (the rail's own
    # labels and LEDs are app/ui/rail_scene.py's).
    hits = [(label.text, led.text) for lname, label in label_boxes(line).items()
            for name, led in leds.items()
            if "/line/" in (lname[:6], name[:6]) and label.overlap(led, tol)]
    assert hits == []


def part(line: Line, name: str) -> Box:
    handle = nodes(line)[name]
    assert isinstance(handle, viser.BoxHandle)
    return solid_box(name, handle)


def within(box: Box, outer: Box, tol: float) -> bool:
    return (outer.x0 - tol <= box.x0 and box.x1 <= outer.x1 + tol
            and outer.z0 - tol <= box.z0 and box.z1 <= outer.z1 + tol)


@pytest.mark.parametrize("state", [s for s in STATES if s.startswith("dc_")] + [
    "cable_0_pulled", "al_codes_and_power", "no_slave_answers", "lost_and_held"])
def test_master_screen_holds_phase_and_dc_state(line: Line, state: str) -> None:
    """The phase and the DC state (seed 003) stay on the master's screen."""
    show(line, state)
    screen, boxes = part(line, "/line/master/screen"), label_boxes(line)
    for key in ("phase", "dc"):
        box = boxes[f"/line/master/{key}"]
        assert within(box, screen, tolerance(line)), box


@pytest.mark.parametrize(("state", "text"), [
    ("cable_0_pulled", "waiting link"), ("no_slave_answers", "no slave answers"),
    ("al_codes_and_power", "init commands"), ("running", "running"),
    ("lost_and_held", "running\n2 lost, 1 held")])
def test_master_screen_names_the_phase_as_the_panel_does(line: Line, state: str,
                                                         text: str) -> None:
    """Seed 003 names no phase "no answer": with link "it starts sending packets", and none
    answers. The screen said "no answer" (whose?); it says what the master reads. "running"
    with slaves lost or held in SAFEOP says so under it: it is not "all is well"."""
    show(line, state)
    assert str(nodes(line)["/line/master/phase"].text) == text


@pytest.mark.parametrize(("state", "text"), [
    (DcState.IDLE, "DC\nidle"), (DcState.SYNCHRONIZING, "DC\nsynchronizing"),
    (DcState.WAITING_START_TIME, "DC\nwaiting start time"),
    (DcState.COMPENSATING, "DC\ncompensating"),
    (DcState.NOT_SYNCHRONIZED, "DC\nnot synchronized")])
def test_master_screen_names_the_dc_state_in_words(line: Line, state: DcState,
                                                   text: str) -> None:
    """Seed 003's DC phase as words, as the phase above it is: the screen showed the
    identifier broken at its underscore, "DC NOT_" / "SYNCHRONIZED"; the Codes tab reads the
    words ("not synchronized") as it reads NOT_SYNCHRONIZED, the master panel's badge."""
    show(line, f"dc_{state.name}")
    assert str(nodes(line)["/line/master/dc"].text) == text


@pytest.mark.parametrize("state", ["running", "every_cable_pulled", "faults", "drive_alarm"])
def test_plate_and_drive_texts_stay_on_their_part(line: Line, state: str) -> None:
    """A module's or an expansion's type within its plate; the drive's ESM state and alarm
    within its front: a text wider than its part runs into the next one's."""
    show(line, state)
    boxes, tol = label_boxes(line), tolerance(line)
    pairs = [(f"/line/cpx/m{n}_t", f"/line/cpx/m{n}") for n in range(1, 5)]
    pairs += [(f"/line/trscat/exp{n}_t", f"/line/trscat/exp{n}") for n in (1, 2)]
    pairs += [("/line/drive_ec-ecat/esm", "/line/drive_ec-ecat/body")]
    if state == "drive_alarm":
        pairs += [("/line/drive_ec-ecat/alarm", "/line/drive_ec-ecat/body")]
    for label, plate in pairs:
        assert within(boxes[label], part(line, plate), tol), (boxes[label], plate)


def unwrap(text: str) -> str:
    """The one-line text back: a line ending in "_" or "-" runs on, others end at a space."""
    out = ""
    for line in text.split("\n"):
        out += line if not out or out[-1] in "_-" else " " + line
    return out


@pytest.mark.parametrize("name", [m.short for m in IO_MODULES.values()]
                         + [short_type(k) for k in EXPANSIONS])
def test_module_types_break_after_a_hyphen_only(name: str) -> None:
    """Seed 002 §2.3.2 (CPX-E-4AI-U-I ...) and seed 001 (TRS-IO-E ...) type names: a long one
    on two lines ("4AI-" / "U-I"), each at most TYPE_LINE characters, nothing lost."""
    text = wrap(name, TYPE_LINE)
    assert unwrap(text) == name
    assert all(len(line) <= TYPE_LINE for line in text.split("\n")), text


def test_the_fault_states_show_the_notes_they_measure(line: Line) -> None:
    """The fault states measure the notes at their longest only if the plates show them:
    the notes follow the model's "error_led", which the states set with "diagnosed"."""
    show(line, "every_module_faulted")
    notes = {name: str(h.text) for name, h in nodes(line).items()
             if isinstance(h, viser.LabelHandle) and name.endswith("_note") and "cpx" in name}
    assert sorted(notes.values()) == ["sensor\nshort", "short\n6 ch.", "wire\n0,2", "wire\n0-3"]
