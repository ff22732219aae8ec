"""An instructor's own action form (an ActionForm: *Module faults*, app/ui/panels/action_form.py)
applies the picked action with its own Parameters, or nothing and says so. A pick is two
writes: viser stores the action on its loop, then the pick's callback builds its Parameters in
viser's thread pool, where Apply's click runs too. ``submit`` read the pick, then the widgets:
an Apply between the two writes sent the new action with the old one's Parameters.

On the AO4, ao_overload and module_failure both take ``active``: the instructor ticked it on
ao_overload, picked module_failure and clicked Apply before its Parameters were built; the
module was failed with a box ticked for the overload, which the instructor never saw on
module_failure's form. The test holds the pick's callback between the two writes.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import Any

import pytest
from pick_race import HOLD_S, off_dashboard

from app.ui.panels.action_form import ActionForm
from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_classroom_leak import Page, _wait, open_class

AO4 = ("ao_overload", "calibrated", "module_failure")  # the fault actions "5 AO4" takes


@pytest.fixture
def form_on_ao4() -> Iterator[tuple[Page, ActionForm]]:
    """The instructor's page and its own Module faults form, on "5 AO4", ao_overload picked
    with its ``active`` ticked."""
    with open_class() as (live, _trainee, instructor):
        copy = _copy(live)
        form: ActionForm = copy.form
        instructor.set(str(copy.module._impl.uuid), "5 AO4")
        _wait(lambda: form.options() == AO4)
        instructor.set(str(form.choice._impl.uuid), "ao_overload")
        _wait(lambda: form._built_for == "ao_overload")
        (param, active), = form._widgets
        assert param.name == "active"
        instructor.set(str(active._impl.uuid), True)
        _wait(lambda: active.value is True)
        yield instructor, form


def _copy(live: ServedRig) -> Any:
    modules = live.dashboard._panels.modules  # type: ignore[union-attr]
    return _wait(lambda: next((c for c in modules._faults._part.each()
                               if c.form is not None), None))


def _notes(page: Page) -> list[str]:
    """The titles and bodies of the notifications this page was shown."""
    return [f"{m['props']['title']}: {m['props']['body']}" for m in page.received()
            if m.get("type") == "NotificationShowMessage"]


def test_an_apply_between_a_pick_and_its_parameters_sends_nothing(
    form_on_ao4: tuple[Page, ActionForm],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    instructor, form = form_on_ao4
    applied: list[tuple[str, dict[str, Any]]] = []
    monkeypatch.setattr(form, "_apply", lambda _client, name, args: applied.append((name, args)))
    entered, release, submitted = threading.Event(), threading.Event(), threading.Event()
    picked, submit = form._picked, form.submit

    def held_picked() -> None:
        if off_dashboard() and not entered.is_set():
            entered.set()  # viser has stored module_failure; its Parameters are to come
            assert release.wait(HOLD_S), "never released"
        picked()

    def spied_submit(client: Any) -> None:
        try:
            submit(client)
        finally:
            submitted.set()

    monkeypatch.setattr(form, "_picked", held_picked)
    monkeypatch.setattr(form, "submit", spied_submit)
    instructor.set(str(form.choice._impl.uuid), "module_failure")
    try:
        assert entered.wait(HOLD_S), "the pick's callback did not run"
        assert form.choice.value == "module_failure" and form._built_for == "ao_overload"
        instructor.set(str(form._button._impl.uuid), True)  # Apply
        assert submitted.wait(HOLD_S), "Apply's callback did not run"
    finally:
        release.set()
    _wait(lambda: form._built_for == "module_failure")
    assert applied == []  # not module_failure with ao_overload's ticked box
    _wait(lambda: any(n.startswith("module_failure not applied") for n in _notes(instructor)))
    # Built, Apply sends module_failure with its own box (unticked: the module has not failed).
    (param, active), = form._widgets
    assert param.name == "active" and active.value is False
    submitted.clear()
    instructor.set(str(form._button._impl.uuid), True)
    assert submitted.wait(HOLD_S)
    assert applied == [("module_failure", {"active": False})]
