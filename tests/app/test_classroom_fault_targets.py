"""With a token, the instructor's own *Slave faults* form lists only what its Target takes,
and an Apply in a fault form is confirmed on the instructor's page only (docs/classroom.md
"What a trainee does not see"). Driven through the websocket, as the browsers drive them."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
from test_classroom_fault_forms import _apply, _in, _read
from test_classroom_leak import Page, _wait, open_class

from app.ui.panels.classroom_rig import ServedRig


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with open_class() as (live, trainee, instructor):
        live.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        live.runtime.advance(1_000_000).result(timeout=30)
        _in(instructor, "Slave faults", "Device")
        yield live, trainee, instructor


def _options(page: Page, uuid: str) -> tuple[str, ...]:
    """The options the page shows now in dropdown ``uuid``: as created, then as updated."""
    shown: tuple[str, ...] = ()
    for m in page.received():
        if m.get("uuid") != uuid:
            continue
        options = (m.get("props") or {}).get("options") or (m.get("updates") or {}).get("options")
        if options:
            shown = tuple(options)
    return shown


def _notes(page: Page) -> list[tuple[str, str, Any]]:
    return [(m["props"]["title"], m["props"]["body"], m["props"]["color"])
            for m in page.received() if m.get("type") == "NotificationShowMessage"]


def test_the_slave_faults_form_on_a_module_lists_its_actions_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    _live, _trainee, instructor = served
    instructor.set(_in(instructor, "Slave faults", "Device"), "cpx")
    action = _in(instructor, "Slave faults", "cpx", "Fault action")
    instructor.set(_in(instructor, "Slave faults", "cpx", "Target"), "cpx/2")
    _wait(lambda: "cable" not in _options(instructor, action))
    shown = set(_options(instructor, action))
    assert not shown & {"cable", "power", "supply"}, shown
    assert {"short_circuit", "inject_fault"} <= shown
    instructor.set(_in(instructor, "Slave faults", "cpx", "Target"), "cpx")
    _wait(lambda: "cable" in _options(instructor, action))
    assert "short_circuit" not in _options(instructor, action)


def test_an_apply_in_a_fault_form_is_confirmed_on_the_instructors_page_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, trainee, instructor = served
    instructor.set(_in(instructor, "Slave faults", "Device"), "cpx")
    instructor.set(_in(instructor, "Slave faults", "cpx", "Target"), "cpx/3")
    action = _in(instructor, "Slave faults", "cpx", "Fault action")
    # the form's list for cpx/3 first: it moves the pick, which the form's rows follow
    _wait(lambda: "cable" not in _options(instructor, action))
    before = len(_notes(instructor))
    _apply(instructor, action, "inject_fault", {"fault": "module_failure"})
    _wait(lambda: _read(live, lambda rig: rig.device("cpx").modules[2].failed))
    _wait(lambda: len(_notes(instructor)) > before)
    [(title, body, color)] = _notes(instructor)[before:]
    assert color == "blue" and "cpx/3" in title and "inject_fault" in title, (title, body)
    assert "module_failure" in body, body
    time.sleep(0.3)
    assert _notes(trainee) == []


@pytest.mark.parametrize(("folder", "action", "params", "title"), [
    ("Module faults", "module_failure", {"active": True}, "fastcat/1: module_failure"),
    ("Drive faults", "inject_alarm", {"code": "16"}, ": inject_alarm"),
])
def test_the_module_and_drive_fault_forms_confirm_too(
        served: tuple[ServedRig, Page, Page], folder: str, action: str,
        params: dict[str, Any], title: str) -> None:
    _live, trainee, instructor = served
    before = len(_notes(instructor))
    _apply(instructor, _in(instructor, folder, "Fault action"), action, params)
    _wait(lambda: len(_notes(instructor)) > before)
    [(said, _body, color)] = _notes(instructor)[before:]
    assert color == "blue" and title in said, said
    assert _notes(trainee) == []


def test_the_instructors_target_list_follows_a_plugged_expansion(
        served: tuple[ServedRig, Page, Page]) -> None:
    """An expansion plugged after the instructor's form was built is offered in its own
    Target list (the pick stays); before, the list was the snapshot of its building."""
    live, _trainee, instructor = served
    instructor.set(_in(instructor, "Slave faults", "Device"), "trscat")
    target = _in(instructor, "Slave faults", "trscat", "Target")
    assert _options(instructor, target) == ("trscat", "trscat/1", "trscat/2")
    instructor.set(target, "trscat/2")
    live.runtime.command("trscat/3", "plug", {"type": "TRS-IO-E"}).result(timeout=10)
    live.runtime.advance(100_000).result(timeout=30)
    _wait(lambda: "trscat/3" in _options(instructor, target))
    assert _options(instructor, target) == ("trscat", "trscat/1", "trscat/2", "trscat/3")
    # The page picked trscat/2 itself; nothing the server sent since moved it.
    moved = [(m.get("updates") or {})["value"] for m in instructor.received()
             if m.get("uuid") == target and "value" in (m.get("updates") or {})]
    assert set(moved) <= {"trscat/2"}, moved
