"""The FastCAT tab's Module I/O form and the Line tab's slave forms are each page's own: the
action picked, its parameters, the actions offered (those of the page's own module or Target)
and what Apply sends (docs/dashboard.md "Several browsers"). Before, they were one form for
every page: page A's pick of an action switched page B's form, B's Apply then sent the action
and values A had chosen, and each form offered what the pages' picks took together. Two
websocket connections stand in for the browsers (tests/app/test_forms_one_drive.py)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest

from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_classroom_leak import Page, _wait
from tests.app.test_forms_per_browser import _frames
from tests.app.test_picks_per_browser import _ids, _settle
from tests.app.two_pages import two_pages

Applied = list[tuple[int, str, dict[str, Any]]]


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages() as pages:
        yield pages


def last_prop(page: Page, uuid: str, prop: str) -> Any:
    """What ``page`` was sent last for ``prop`` of the widget ``uuid`` (built or updated)."""
    value = None
    for m in page.received():
        if m.get("uuid") != uuid:
            continue
        if prop in (m.get("props") or {}):
            value = m["props"][prop]
        if prop in (m.get("updates") or {}):
            value = m["updates"][prop]
    return value


def _uuid(handle: Any) -> str:
    return str(getattr(handle, "handle", handle)._impl.uuid)


def _recorded(form: Any) -> Applied:
    """What ``form``'s Apply hands on from now on (the model is not asked)."""
    applied: Applied = []
    form._apply = lambda client, name, args: applied.append(  # type: ignore[method-assign]
        (client.client_id, name, dict(args)))
    return applied


def _button(form: Any) -> str:
    return _uuid(form.button)


def test_module_i_o_is_each_page_s_own(served: tuple[ServedRig, Page, Page]) -> None:
    """A picks module 3 (a DO16) and output_short on it; B (module 1, a DB16) keeps its own
    list, its own pick and its own Apply."""
    live, first, second = served
    modules = live.dashboard._panels.modules  # type: ignore[union-attr]
    form = modules._form
    choice = _uuid(form.choice)
    first.set(_uuid(modules.pick), "3 DO16")
    _settle(live)
    _settle(live)  # module 3's actions read and offered
    _wait(lambda: last_prop(first, choice, "options") == ["module_failure", "output_short"])
    assert "set_input" in last_prop(second, choice, "options")  # B's DB16 takes it
    first.set(choice, "output_short")
    time.sleep(0.2)
    first.set(_uuid(form.field("output_short", "channel")), 4)
    time.sleep(0.2)
    _frames(live)
    assert "output_short" not in second.updates(choice)  # (B's own moves are its list's)
    applied = _recorded(form)
    second.set(_button(form), True)
    _wait(lambda: applied)
    one, two = _ids(live)
    assert applied[0][:2] == (two, "module_failure")  # B's own pick: its list's first
    first.set(_button(form), True)
    _wait(lambda: len(applied) == 2)
    assert applied[1][0] == one and applied[1][1] == "output_short"
    assert applied[1][2]["channel"] == 4


def test_the_slave_form_is_each_page_s_own(served: tuple[ServedRig, Page, Page]) -> None:
    """The CPX-E-EC's form: A's Target cpx/1 (a 16DI) and its set_input with channel 5; B's
    Target stays the device, whose list is the device's (set_dil, restart, ...)."""
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    _folder, form = controls.forms["cpx"]
    choice = _uuid(form.choice)
    first.set(_uuid(controls.targets["cpx"]), "cpx/1")
    _settle(live)
    _settle(live)
    _wait(lambda: "set_input" in (last_prop(first, choice, "options") or ()))
    assert "set_dil" not in last_prop(first, choice, "options")
    assert "set_input" not in last_prop(second, choice, "options")
    assert "set_dil" in last_prop(second, choice, "options")
    first.set(choice, "set_input")
    time.sleep(0.2)
    first.set(_uuid(form.field("set_input", "channel")), 5)
    time.sleep(0.2)
    _frames(live)
    assert "set_input" not in second.updates(choice)
    applied = _recorded(form)
    first.set(_button(form), True)
    _wait(lambda: applied)
    one, two = _ids(live)
    assert applied[0][0] == one and applied[0][1] == "set_input"
    assert applied[0][2]["channel"] == 5
    second.set(_button(form), True)
    _wait(lambda: len(applied) == 2)
    assert applied[1][0] == two and applied[1][1] == form.options(two)[0] != "set_input"


def test_a_fault_form_s_pick_stays_on_its_page(served: tuple[ServedRig, Page, Page]) -> None:
    """An open rig's *trscat faults* form: A's pick of field_supply does not move B's."""
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    form = controls.fault_forms["trscat"]
    choice = _uuid(form.choice)
    first.set(choice, "field_supply")
    _frames(live)
    assert "field_supply" not in second.updates(choice)
    first.set(_uuid(form.field("field_supply", "volts")), 12.5)
    _frames(live)
    applied = _recorded(form)
    first.set(_button(form), True)
    _wait(lambda: applied)
    assert applied[0][1:] == ("field_supply", {"volts": 12.5})


def test_set_dil_starts_from_the_switches_on_the_page_that_picks_it(
        served: tuple[ServedRig, Page, Page]) -> None:
    """Param.current (seed 002 §2.1.7): the picking page's boxes start from the switches as
    they are now (the default rig's DIL 1 ON / DIL 2 OFF moved to OFF / ON), the other
    page's stay as they were."""
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    _folder, form = controls.forms["cpx"]
    live.runtime.command("cpx", "set_dil", {"dil1": False, "dil2": True}).result(timeout=10)
    first.set(_uuid(controls.targets["cpx"]), "cpx")
    _settle(live)
    dil1, dil2 = _uuid(form.field("set_dil", "dil1")), _uuid(form.field("set_dil", "dil2"))
    first.set(_uuid(form.choice), "set_dil")
    _wait(lambda: first.updates(dil1) == [False] and first.updates(dil2) == [True])
    _frames(live)
    assert second.updates(dil1) == [] and second.updates(dil2) == []
    live.runtime.command("cpx", "set_dil", {"dil1": True, "dil2": False}).result(timeout=10)
