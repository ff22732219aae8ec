"""The instructor's own fault forms act on what the instructor picked in them, and a trainee
keeps the operator's forms (docs/classroom.md "What a trainee does not see").

With a token the FastCAT's Module I/O and the drive's Other drive actions keep only what an
operator does; their fault actions, and the Line tab's slave fault forms, are a form per
instructor connection with pickers of its own (Module; Device and Target). Driven as the
browsers drive them: through the websocket, the instructor's widgets found in its own page.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
from test_classroom_leak import Page, _try, _wait, open_class

from app.ui.panels.classroom_rig import ServedRig


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with open_class() as (live, trainee, instructor):
        for target, action, args in (
            ("fastcat", "power", {"on": True}),
            ("master", "set_target", {"state": "OP"}),
        ):
            live.runtime.command(target, action, args).result(timeout=10)
        live.runtime.advance(3_000_000).result(timeout=30)
        _wait(lambda: _try(instructor.last, "Module", "4 AI8D"))
        yield live, trainee, instructor


def _apply(page: Page, picker: str, action: str, params: dict[str, Any]) -> None:
    """Pick ``action`` in the form whose picker is ``picker`` (a uuid), fill its parameters
    and click Apply. An instructor's own form (an ActionForm) builds its one Parameters
    folder's rows anew when the pick changes (the rows after it); a shared one (a
    ClientActionForm, each page's own) has a folder per action, shown to the page that
    picked it."""
    shown = [
        m.get("value") for m in page.received() if m.get("uuid") == picker and "props" in m
    ] + page.updates(picker)
    mark = len(page.received())
    before = 0 if shown[-1] == action else mark
    page.set(picker, action)
    picked = next(m for m in page.received() if m.get("uuid") == picker)
    container = picked["container_uuid"]
    folders = [
        m["uuid"]
        for m in page.received()
        if m.get("container_uuid") == container
        and (m.get("props") or {}).get("label") == "Parameters"
    ]
    if len(folders) > 1:  # each page's own form: the folder its pick shows on this page
        folder = _wait(lambda: next((
            m["uuid"] for m in page.received()[mark:]
            if m.get("uuid") in folders and (m.get("updates") or {}).get("visible") is True),
            None))
        before = 0
    else:
        folder = folders[0]
    for label, value in params.items():
        param = _wait(
            lambda label=label: next(
                (
                    m["uuid"]
                    for m in reversed(page.received()[before:])
                    if m.get("container_uuid") == folder
                    and (m.get("props") or {}).get("label") == label
                ),
                None,
            )
        )
        page.set(param, value)
    time.sleep(0.3)  # the values arrive before the click
    apply = next(
        m["uuid"]
        for m in page.received()
        if m.get("container_uuid") == container and (m.get("props") or {}).get("label") == "Apply"
    )
    page.set(apply, True)


def _in(page: Page, *path: str) -> str:
    """The uuid of the widget ``path[-1]`` in the folder ``path[-2]``, that folder in
    ``path[-3]`` and so on (each the page's newest folder so titled in the one before), once
    the page has it. The instructor's own folders come on its connection's own messages, the
    server-level ones (the Slave tab's "cpx" form, with a Target too) on the replay of the
    shared elements: two producers in no set order, so the newest "cpx" may be the shared
    one. A folder whose title a shared folder also has is named with its parent's
    ("Slave faults", "cpx")."""
    *folders, label = path
    assert folders, "name the widget's folder"

    def found() -> str | None:
        got = page.received()
        parent: str | None = None
        for depth, title in enumerate(folders):
            parent = next((str(m["uuid"]) for m in reversed(got)
                           if m.get("type") == "GuiFolderMessage"
                           and (m.get("props") or {}).get("label") == title
                           and (depth == 0 or m.get("container_uuid") == parent)), None)
            if parent is None:
                return None
        return next((str(m["uuid"]) for m in got if m.get("container_uuid") == parent
                     and (m.get("props") or {}).get("label") == label), None)

    return str(_wait(found))


def _read(live: ServedRig, fn: Any) -> Any:
    return live.runtime.submit(lambda: fn(live.rig)).result(timeout=10)


def test_the_instructor_fails_the_module_picked_in_its_own_form(
    served: tuple[ServedRig, Page, Page],
) -> None:
    live, _trainee, instructor = served
    instructor.set(_in(instructor, "Module faults", "Module"), "4 AI8D")
    time.sleep(0.3)
    _apply(
        instructor,
        _in(instructor, "Module faults", "Fault action"),
        "module_failure",
        {"active": True},
    )
    _wait(lambda: _read(live, lambda rig: rig.device("fastcat").rail_module(4).failed))
    assert not _read(live, lambda rig: rig.device("fastcat").rail_module(1).failed)


def test_the_instructor_injects_a_drive_alarm_from_its_own_form(
    served: tuple[ServedRig, Page, Page],
) -> None:
    live, _trainee, instructor = served
    drive = live.dashboard.drives.selected  # type: ignore[union-attr]
    _apply(
        instructor, _in(instructor, "Drive faults", "Fault action"), "inject_alarm", {"code": "16"}
    )
    _wait(lambda: _read(live, lambda rig: rig.device(drive).snapshot()["injected"]))


def test_the_instructor_injures_the_slave_and_module_picked_in_its_own_form(
    served: tuple[ServedRig, Page, Page],
) -> None:
    live, _trainee, instructor = served
    instructor.set(_in(instructor, "Slave faults", "Device"), "cpx")
    instructor.set(_in(instructor, "Slave faults", "cpx", "Target"), "cpx/3")
    time.sleep(0.3)
    _apply(
        instructor,
        _in(instructor, "Slave faults", "cpx", "Fault action"),
        "inject_fault",
        {"fault": "module_failure"},
    )
    _wait(lambda: _read(live, lambda rig: rig.device("cpx").modules[2].failed))


def test_a_trainee_keeps_the_operators_module_form(served: tuple[ServedRig, Page, Page]) -> None:
    """set_input on a module: a sensor on an input, what an operator does with the rail."""
    live, trainee, _instructor = served
    module = trainee.widget("Module")  # the shared one: a trainee gets no other
    trainee.set(module, "1 DB16")
    time.sleep(0.3)
    # Module I/O's picker (the drive's and the CPX-E-EC's forms have a set_input too), once
    # it offers what a DB16 takes (the form follows the module picked).
    picker = _in(trainee, "Module I/O", "Action")
    _wait(
        lambda: (
            ["set_input"]
            in [
                m["updates"].get("options")
                for m in trainee.received()
                if m.get("uuid") == picker and "updates" in m
            ]
        )
    )
    time.sleep(0.3)
    _apply(trainee, picker, "set_input", {"channel": 3, "value": True})
    _wait(lambda: _read(live, lambda rig: rig.device("fastcat").rail_module(1)._dig().field[2]))


def test_the_instructor_powers_off_the_module_picked_in_its_own_rail_rows(
    served: tuple[ServedRig, Page, Page],
) -> None:
    """The Rail / Module powered rows acted on the shared Module picker: picking the module to
    switch off moved every trainee's picker to it. With a token they have their own."""
    live, trainee, instructor = served
    instructor.set(_in(instructor, "Rail and power", "Module"), "6 AI8TC")
    time.sleep(0.3)
    instructor.set(_in(instructor, "Rail and power", "Module powered"), False)
    _wait(lambda: not _read(live, lambda rig: rig.device("fastcat").rail_module(6).powered))
    assert _read(live, lambda rig: rig.device("fastcat").rail_module(1).powered)
    time.sleep(0.5)
    shared = trainee.widget("Module")  # the shared picker: a trainee gets no other
    assert "6 AI8TC" not in trainee.updates(shared)
    assert "6 AI8TC" not in [m.get("value") for m in trainee.received()]
    _read(live, lambda rig: rig.apply("fastcat/6", "module_power", {"on": True}))


def test_the_instructor_jams_the_drive_picked_in_its_own_alarm_rows(
    served: tuple[ServedRig, Page, Page],
) -> None:
    """Alarms and load acted on the shared Servo drive picker (every page's Drive tab)."""
    live, trainee, instructor = served
    assert live.dashboard.drives.selected == "drive"  # type: ignore[union-attr]
    instructor.set(_in(instructor, "Alarms and load", "Drive"), "drive_co")
    time.sleep(0.3)
    instructor.set(_in(instructor, "Alarms and load", "Load jammed"), True)
    _wait(lambda: _read(live, lambda rig: rig.device("drive_co").snapshot()["jammed"]))
    assert not _read(live, lambda rig: rig.device("drive").snapshot()["jammed"])
    # The drive faults form acts on its own pick too.
    instructor.set(_in(instructor, "Drive faults", "Drive"), "drive_ec")
    time.sleep(0.3)
    _apply(instructor, _in(instructor, "Drive faults", "Fault action"), "jam_load",
           {"active": True})
    _wait(lambda: _read(live, lambda rig: rig.device("drive_ec").snapshot()["jammed"]))
    time.sleep(0.5)
    assert live.dashboard.drives.selected == "drive"  # type: ignore[union-attr]
    picked = trainee.updates(trainee.widget("Servo drive"))
    assert "drive_co" not in picked and "drive_ec" not in picked
    for drive in ("drive_co", "drive_ec"):
        _read(live, lambda rig, d=drive: rig.apply(d, "jam_load", {"active": False}))

def _causes_text(page: Page) -> str:
    """Every content sent to an HTML element of the page's *Slave causes* folders."""
    received = page.received()
    folders = {m["uuid"] for m in received if m.get("type") == "GuiFolderMessage"
               and (m.get("props") or {}).get("label") == "Slave causes"}
    tables = {m["uuid"] for m in received
              if m.get("type") == "GuiHtmlMessage" and m.get("container_uuid") in folders}
    return " ".join(str((m.get("updates") or m.get("props") or {}).get("content", ""))
                    for m in received if m.get("uuid") in tables)


def _causes_state(live: ServedRig, page: Page) -> str:
    """Where the causes stood when the page did not get them: each instructor copy's pick and
    table, the frames drawn, what the model says of module 2, what the page got."""
    line = live.dashboard.line
    assert line is not None
    forms = [(f.picker.value, str(f.html.content)) for f in line.slave._causes.each()]
    cpx = (live.runtime.frame.snapshot.get("devices") or {}).get("cpx") or {}
    module = next((m for m in cpx.get("modules") or [] if m.get("module") == 2), {})
    return (f"server copies {forms}; drawn frame {live.dashboard.rendered_seq} of "
            f"{live.runtime.frame.seq}; cpx module 2 undiagnosed {module.get('undiagnosed')}, "
            f"error LED {module.get('error_led')}; the page got {_causes_text(page)[-2000:]!r}")


def test_the_instructor_reads_the_causes_of_the_slave_picked_in_its_own_picker(
    served: tuple[ServedRig, Page, Page],
) -> None:
    """The Slave tab's Injected rows were the shared Slave picker's slave: to read a slave's
    causes the instructor picked it there, on every trainee's page too."""
    live, trainee, instructor = served
    line = live.dashboard.line
    assert line is not None and line.slave.selected == "trscat"
    _read(live, lambda rig: rig.apply("cpx/2", "inject_fault",
                                      {"fault": "short_circuit", "channel": 3}))
    live.runtime.advance(500_000).result(timeout=30)
    instructor.set(_in(instructor, "Slave causes", "Slave"), "cpx")
    # Looked up inside the wait: a folder found right after the pick may be one the page is
    # about to get again under a new id (CI saw the wait follow such a stale table).
    try:
        _wait(lambda: "short 3" in _causes_text(instructor))
    except AssertionError as timed_out:  # once in CI (2026-11-28): say where it stopped
        raise AssertionError(_causes_state(live, instructor)) from timed_out
    time.sleep(0.5)
    assert line.slave.selected == "trscat"
    assert "cpx" not in trainee.updates(trainee.widget("Slave", "trscat"))
    _read(live, lambda rig: rig.apply("cpx/2", "clear_fault",
                                      {"fault": "short_circuit", "channel": 3}))
