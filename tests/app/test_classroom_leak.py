"""Nothing that names an injected cause or an instructor's fault pick reaches a trainee's
browser (docs/classroom.md "What a trainee does not see"). The causes were rows of the shared
state tables and the fault pickers server-level widgets, hidden by the trainee's CSS only: the
page's HTML held "0x0B TARATURA on module 4" and the picked ``value="0x0B TARATURA"``, for
any trainee who opened the developer tools. Two websocket connections stand in for the
browsers; what each receives is viser's wire messages."""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import msgspec
import pytest
from viser_page import Page
from viser_page import wait as _wait

from app.classroom.roles import Access, Role
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.panels.classroom_rig import ServedRig, serve_rig

TOKEN = "s3cret"


def values(page: Page) -> list[Any]:
    """Every widget value the page was given: at creation and by later updates."""
    found = []
    for m in page.received():
        if "value" in m and "props" in m:
            found.append(m["value"])
        if m.get("type") == "GuiUpdateMessage" and "value" in (m.get("updates") or {}):
            found.append(m["updates"]["value"])
    return found


def options(page: Page) -> set[str]:
    """Every dropdown option the page was offered: at creation and by later updates."""
    found: set[str] = set()
    for m in page.received():
        found.update((m.get("props") or {}).get("options") or ())
        found.update((m.get("updates") or {}).get("options") or ())
    return found


def text(page: Page) -> str:
    return msgspec.json.encode(page.received()).decode()


@contextmanager
def open_class(exercise_files: Sequence[Path] = ()) -> Iterator[tuple[ServedRig, Page, Page]]:
    """The default rig served paused with the token (and ``exercise_files``), a trainee's page
    and the instructor's (the second page, promoted as if it had shown the token); all closed
    on exit."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    live = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True,
                     exercise_files=exercise_files)
    trainee, instructor = Page(live.port), Page(live.port)
    try:
        clients = _wait(lambda: len(live.server.get_clients()) == 2 and live.server.get_clients())
        first, second = sorted(clients)
        assert live.classroom.access.present(second, TOKEN)
        live.classroom._promoted(clients[second])
        assert live.classroom.access.role(first) is Role.TRAINEE
        yield live, trainee, instructor
    finally:
        trainee.close()
        instructor.close()
        live.stop()
    # A reader thread that died after the test's last read fails the test here, not silently.
    trainee.check()
    instructor.check()


@pytest.fixture(scope="module")
def pages() -> Iterator[tuple[Page, Page]]:
    """A trainee's and the instructor's page after the instructor picked and injected a module
    fault (0x0B on module 4) from its page, a coupler code, pulled the line's cable 2,
    jammed the Modbus drive's load and switched module 3's supply off."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    trainee, instructor = Page(served.port), Page(served.port)
    try:
        _play(served, trainee, instructor)
        yield trainee, instructor
    finally:
        trainee.close()
        instructor.close()
        served.stop()
    trainee.check()
    instructor.check()


def _command(served: ServedRig, target: str, action: str, args: dict[str, Any]) -> None:
    served.runtime.command(target, action, args).result(timeout=10)


def _play(served: ServedRig, trainee: Page, instructor: Page) -> None:
    clients = _wait(lambda: len(served.server.get_clients()) == 2
                    and served.server.get_clients())
    first, second = sorted(clients)
    # The instructor showed the token (its page's localStorage, simulated).
    assert served.classroom.access.present(second, TOKEN)
    served.classroom._promoted(clients[second])
    assert served.classroom.access.role(first) is Role.TRAINEE
    _wait(lambda: "Hidden fault" in text(instructor))
    # The instructor picks a module fault on module 4 and injects it, from the page.
    table = _wait(lambda: _try(instructor.widget, "Table"))
    instructor.set(table, "module codes (§7.6)")
    time.sleep(0.3)
    instructor.set(instructor.widget("Fault"), "0x0B TARATURA")
    # The Target box lists the rail's modules once the coupler has numbered them.
    _command(served, "fastcat", "power", {"on": True})
    _command(served, "master", "set_target", {"state": "OP"})
    served.runtime.advance(3_000_000).result(timeout=30)
    _wait(lambda: "4 AI8D" in str([m.get("updates") for m in instructor.received()
                                    if m.get("type") == "GuiUpdateMessage"]))
    instructor.set(instructor.widget("Target", "coupler (no module)"), "4 AI8D")
    time.sleep(0.3)  # the picks arrive before the click
    instructor.set(instructor.widget("Injection"), "Inject")
    _wait(lambda: served.runtime.submit(served.rig.snapshot).result(timeout=5)
          ["devices"]["fastcat"]["injected"])
    # A coupler cause, and the line's cable 2 picked and pulled in the Line tab.
    _command(served, "fastcat", "inject_fault", {"fault": "coupler:0x04"})
    instructor.set(instructor.widget("Cable"), "2 trscat -> cpx")
    time.sleep(0.3)
    instructor.set(instructor.widget("Cable plug"), "Pull")
    _wait(lambda: "0x0B TARATURA on module 4" in text(instructor))
    _wait(lambda: "2 trscat -> cpx (pulled)" in values(instructor))
    # The slave behind the pulled cable switched off too: the instructor's Slave to power
    # list marks it (the supply is the master's ``injected``).
    _command(served, "master", "power_slave", {"position": 2, "on": False})
    served.runtime.advance(100_000).result(timeout=30)  # its supply's hold-up time
    _wait(lambda: "2 cpx (off)" in options(instructor))
    _wait(lambda: "0x04 MISSING_NODE_ANSWER" in text(instructor))
    # A physical cause on the Modbus drive: the load jammed (the Alarms and load folder's box).
    _command(served, "drive", "jam_load", {"active": True})
    served.runtime.advance(100_000).result(timeout=30)
    _wait(lambda: "load jammed" in text(instructor))
    # The FastCAT's Module I/O and the drive's Other drive actions: the instructor picks a
    # module to fail and a fault action in each (the shared forms offered them to everyone).
    instructor.set(instructor.own(trainee, "Module", "4 AI8D"), "4 AI8D")
    time.sleep(0.3)
    instructor.set(instructor.own(trainee, None, "module_failure"), "module_failure")
    instructor.set(instructor.own(trainee, None, "inject_alarm"), "inject_alarm")
    # The Line tab: the instructor picks the slave and the module to injure.
    instructor.set(instructor.own(trainee, "Device", "cpx"), "cpx")
    time.sleep(0.3)
    instructor.set(instructor.own(trainee, "Target", "cpx/2"), "cpx/2")
    # An alarm cause put on the drive the Drive tab shows and taken away again (the
    # exercise's repair of a right answer does the same).
    drive = served.dashboard.drives.selected  # type: ignore[union-attr]
    _command(served, drive, "inject_alarm", {"code": "16"})
    _command(served, drive, "clear_alarm", {"code": "16"})
    served.runtime.advance(100_000).result(timeout=30)
    _wait(lambda: "alarm 16 FOLLOWING_ERROR" in text(instructor))
    # The Rail and power folder's Module powered box: module 3 without supply.
    _command(served, "fastcat/3", "module_power", {"on": False})
    served.runtime.advance(100_000).result(timeout=30)
    _wait(lambda: "its supply is off" in text(instructor))
    time.sleep(1.0)  # what the trainee would get has had the time to arrive


def test_a_trainee_receives_no_injected_cause(pages: tuple[Page, Page]) -> None:
    trainee, instructor = pages
    assert "<th>Injected</th>" in text(instructor)  # the instructor sees the causes
    got = text(trainee)
    assert "ESM state" in got  # the trainee did get the state table
    # The Codes tab decodes a reported code: when that is the FastCAT's emergency (§7) it
    # names the module code as the State tab's Alarm row does, a symptom every page shows.
    got = got.replace("Module alarm 0x0B TARATURA on module 4: ", "")
    for leak in ("TARATURA on module", "MISSING_NODE_ANSWER on", "<th>Injected</th>",
                 "<th>Causes</th>"):
        assert leak not in got, leak


def test_a_trainee_receives_no_line_cause_from_the_master(pages: tuple[Page, Page]) -> None:
    """The master's log, diagnostics and Line tab say what a real master observes (the
    slaves from position 2 on do not answer); the cable is the instructor's Injected / Causes
    rows (docs/ethercat-master.md "What the master knows"). Before, the log line ended
    "(cable 2 pulled)." and the Line tab's shared Cables row read "2 trscat -> cpx pulled"."""
    trainee, instructor = pages
    assert "2: cable 2 pulled" in text(instructor)  # the instructor's Causes row
    got = text(trainee)
    assert "no answer from position 2 on" in got  # the trainee did get the master's finding
    for leak in ("cable 2 pulled)", "trscat -&gt; cpx pulled", "<th>Cables</th>",
                 "2: cable 2 pulled"):
        assert leak not in got, leak


def test_a_trainee_is_not_told_which_slave_is_switched_off(pages: tuple[Page, Page]) -> None:
    """The Master folder's "ESC counters of" list is everyone's (clearing the counters is a
    trainee's diagnosis) but it was filled from the instructor's Slave to power options,
    which mark a slave without supply "(off)" from the master's ``injected``: a real master
    cannot tell a slave switched off from a cable pulled (docs/ethercat-master.md "What the
    master knows"), so every trainee read which slave the instructor had switched off."""
    trainee, instructor = pages
    assert "2 cpx (off)" in options(instructor)
    offered = options(trainee)
    assert "2 cpx" in offered  # the trainee did get the shared list
    assert not [o for o in offered if o.endswith("(off)")]


def test_a_trainee_receives_no_jammed_load(pages: tuple[Page, Page]) -> None:
    """The jam named itself on every page: the Drive tab's TEN / IEN badge, the 3D caption
    under the axis ("switches: home · load jammed") and the Drive log line; a trainee must
    see only its symptoms (the axis not following, alarm 16 when it moves)."""
    trainee, instructor = pages
    assert "load jammed" in text(instructor)  # the instructor's causes table
    got = text(trainee)
    assert "TEN " in got and "switches: " in got  # the trainee did get the row and the caption
    # "jammed" is in a scenario's title in the Scenario tab's list: that is no cause.
    assert "load jammed" not in got.lower()
    assert got.count("jammed") == got.count("error on a jammed load")


def test_a_trainee_receives_no_fault_pick(pages: tuple[Page, Page]) -> None:
    trainee, instructor = pages
    assert "Hidden fault" not in text(trainee)
    # The instructor's own picks are not echoed to its page (viser sends a page's change to
    # the other pages: that is how the trainees got them); the pulled cable's new label is.
    assert "2 trscat -> cpx (pulled)" in values(instructor)
    picked = values(trainee)
    for pick in ("0x0B TARATURA", "4 AI8D", "2 trscat -> cpx (pulled)", "2 trscat -> cpx",
                 "module codes (§7.6)"):
        assert pick not in picked, pick


def _try(fn: Any, *args: Any) -> Any:
    try:
        return fn(*args)
    except KeyError:
        return None


# Actions that make a fault in some direction (roles.makes_faults) on the FastCAT's modules and
# the drives: a trainee's page is offered none of them, in no form.
FAULT_ACTIONS = ("module_failure", "encoder_fault", "output_short", "calibrated",
                 "inject_fault", "clear_fault", "inject_alarm", "clear_alarm", "jam_load")


def test_a_trainee_is_offered_no_fault_action(pages: tuple[Page, Page]) -> None:
    """The FastCAT's Module I/O form and the drive's Other drive actions were shared: every
    page got their fault actions, and the instructor's pick of one (module_failure,
    inject_alarm) and of its module went to every trainee."""
    trainee, instructor = pages
    assert {"module_failure", "inject_alarm"} <= options(instructor)
    offered = options(trainee)
    # What an operator does stays the trainee's: the module's inputs, the drive's commands.
    assert {"set_input", "set_analog", "move", "read_register"} <= offered
    for action in FAULT_ACTIONS:
        assert action not in offered, action
    picked = values(trainee)
    for pick in ("module_failure", "inject_alarm", "4 AI8D"):
        assert pick not in picked, pick


def test_a_trainee_does_not_see_the_slave_picked_to_injure(pages: tuple[Page, Page]) -> None:
    """The Line tab's Device and Target pickers were the ones a fault form acted on: picking
    cpx and its module 2 to injure moved them on every page."""
    trainee, _instructor = pages
    assert "cpx/2" not in values(trainee)
    assert "cpx" not in trainee.updates(trainee.widget("Device", "cpx"))


def test_a_trainee_is_not_told_a_cause_was_removed(pages: tuple[Page, Page]) -> None:
    """The drive's "cause of alarm 16 removed" line (the instructor's clear_alarm) reached the
    trainees' Drive log: the drive itself logs no such thing, its alarm stays latched until a
    reset. The alarm the drive raised is in the log for everyone."""
    trainee, _instructor = pages
    got = text(trainee)
    assert "alarm 16 FOLLOWING_ERROR raised" in got
    assert "cause of alarm" not in got


def _cable_nodes(page: Page, index: int) -> list[dict[str, Any]]:
    """The scene nodes of the line's cable ``index`` this page was sent, in order."""
    root = f"/line/cable{index}/"
    return [m for m in page.received() if str(m.get("name", "")).startswith(root)
            and m.get("type") in ("BoxMessage", "LabelMessage")]


def _drawn(nodes: list[dict[str, Any]]) -> tuple[set[tuple[int, ...]], list[str]]:
    return ({tuple(m["props"]["color"]) for m in nodes if m["type"] == "BoxMessage"},
            [m["props"]["text"] for m in nodes if m["type"] == "LabelMessage"])


def test_a_trainee_s_scene_shows_no_pulled_cable(pages: tuple[Page, Page]) -> None:
    """The 3D line drew the instructor's pulled cable 2 red and hanging, labelled "cable 2
    pulled", on every page. A trainee sees what the real rig shows: the cable in its ports
    (the LINK / ACT LEDs at both ends dark); the instructor's page still shows it pulled."""
    from app.ui.line.cables import PLUGGED, PULLED

    trainee, instructor = pages
    colours, labels = _drawn(_cable_nodes(trainee, 2))
    assert labels and colours  # the trainee did get the cable
    assert colours == {PLUGGED} and all("pulled" not in t for t in labels), (colours, labels)
    colours, labels = _drawn(_cable_nodes(instructor, 2))
    assert PULLED in colours and "pulled" in labels[-1], (colours, labels)


def test_the_instructor_s_scene_shows_the_jammed_load(pages: tuple[Page, Page]) -> None:
    """The shared axis leaves the jam out with a token (the red carriage, "load jammed" in
    its caption); the instructor's page draws them over it, its own scene nodes."""
    from app.ui.drive.axis_scene import CARRIAGE_JAMMED

    trainee, instructor = pages
    for page, shown in ((instructor, True), (trainee, False)):
        nodes = [m for m in page.received() if str(m.get("name", "")).startswith("/drive_axis/")]
        red = any(tuple((m.get("props") or {}).get("color") or ()) == CARRIAGE_JAMMED
                  for m in nodes)
        caption = any("load jammed" in str((m.get("props") or {}).get("text", ""))
                      for m in nodes)
        assert (red, caption) == (shown, shown), page


def test_a_trainee_s_rail_shows_no_module_switched_off(pages: tuple[Page, Page]) -> None:
    """The 3D rail greyed module 3 and wrote "power off" under it on every page, while the
    Causes row that says "its supply is off" and the Module powered box are the
    instructor's: a trainee sees what the real module shows, its LEDs dark. The instructor's
    page draws the module as it is, its own scene nodes over the shared ones."""
    from app.ui.rail_scene import BODY_UNPOWERED

    trainee, instructor = pages
    for page, shown in ((instructor, True), (trainee, False)):
        nodes = [m for m in page.received()
                 if str(m.get("name", "")).startswith("/fastcat/slot03/")]
        assert nodes, page  # the page did get the slot
        grey = any(tuple((m.get("props") or {}).get("color") or ()) == BODY_UNPOWERED
                   for m in nodes if m["name"].endswith("/body"))
        note = any("power off" in str((m.get("props") or {}).get("text", "")) for m in nodes)
        assert (grey, note) == (shown, shown), page
