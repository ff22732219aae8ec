"""An instructor's own action form (an ActionForm: *Module faults*, *Slave faults*) offers the
actions its module or Target takes and keeps the instructor's pick while it is offered,
whichever of its two writers comes last (app/ui/panels/action_form.py): the instructor's pick
(viser stores it, its callback builds the Parameters in viser's thread pool) and the frame
update's ``restrict`` (the dashboard thread), which writes a new list of actions.

``restrict`` read the pick, worked out what to keep, wrote the list, then wrote the pick it had
read: a pick made in between was undone, and the form stayed on the action the instructor had
left until they picked again. A pick of an action the list no longer held (made on the page's
list before the new one reached it) that came after ``restrict`` stayed, its Parameters
built, and Apply sent the module an action it refuses, until the next list change. The first
test holds ``restrict`` between its read and its write while the instructor picks.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import Any

import pytest
from pick_race import HOLD_S, SpyLock, off_dashboard, on_dashboard

from app.classroom.roles import Role
from app.ui.panels.action_form import ActionForm
from app.ui.panels.classroom_rig import ServedRig
from app.ui.panels.client_pick import send_to
from tests.app.test_action_forms_per_page import last_prop
from tests.app.test_classroom_leak import Page, _wait, open_class

DB16 = ("module_failure", "output_short")  # what "1 DB16" takes of the fault actions
AO4 = ("ao_overload", "calibrated", "module_failure")  # and "5 AO4"
MARK = "fr-test-mark"


class _HeldChoice:
    """The form's action picker as the dashboard thread sees it: once armed, its next write of
    the options (``restrict``, after it read the pick) waits for ``release``."""

    def __init__(self, real: Any) -> None:
        object.__setattr__(self, "_real", real)
        object.__setattr__(self, "armed", False)
        object.__setattr__(self, "entered", threading.Event())
        object.__setattr__(self, "release", threading.Event())

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "armed":
            object.__setattr__(self, name, value)
            return
        if name == "options" and self.armed and on_dashboard():
            object.__setattr__(self, "armed", False)
            self.entered.set()
            assert self.release.wait(HOLD_S), "never released"
        setattr(self._real, name, value)


@pytest.fixture
def faults() -> Iterator[tuple[ServedRig, Page, Any]]:
    """The instructor's page and its own Module faults copy, on module 1 (a DB16)."""
    with open_class() as (live, _trainee, instructor):
        modules = live.dashboard._panels.modules  # type: ignore[union-attr]
        copy = _wait(lambda: next((c for c in modules._faults._part.each()
                                   if c.form is not None), None))
        _wait(lambda: copy.form.options() == DB16)
        yield live, instructor, copy


def _drawn(live: ServedRig) -> None:
    seq = live.runtime.frame.seq
    _wait(lambda: live.dashboard.rendered_seq >= seq)


def test_a_pick_during_restrict_is_not_undone_by_it(
    faults: tuple[ServedRig, Page, Any],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The form on output_short (DB16); its Module moved to the AO4, whose list lacks it;
    restrict read output_short and settled on the new list's first, ao_overload; the instructor
    picked module_failure, which both lists hold; then restrict wrote ao_overload over it."""
    live, instructor, copy = faults
    form: ActionForm = copy.form
    choice = str(form.choice._impl.uuid)
    instructor.set(choice, "output_short")
    _wait(lambda: form.choice.value == "output_short" and form._built_for == "output_short")
    held, spy = _HeldChoice(form._choice), SpyLock(off_dashboard)
    monkeypatch.setattr(form, "_choice", held)
    monkeypatch.setattr(form, "_lock", spy)  # the form's lock
    _drawn(live)
    held.armed = True
    try:
        instructor.set(str(copy.module._impl.uuid), "5 AO4")
        assert held.entered.wait(HOLD_S), "the frame update did not restrict the form"
        before = len(instructor.updates(choice))
        instructor.set(choice, "module_failure")
        # The pick's callback has built it, or waits for restrict to end first.
        _wait(lambda: form._built_for == "module_failure" or spy.waiting.is_set())
    finally:
        held.release.set()
    _drawn(live)
    assert form.options() == AO4
    # Nothing writes the pick again before the next list change: an undone pick stays.
    _wait(lambda: form.choice.value == "module_failure", timeout=5)
    _wait(lambda: form._built_for == "module_failure", timeout=5)
    # The page shows its own pick unless sent another: everything sent before this mark is in.
    client = next(c for i, c in live.server.get_clients().items()
                  if live.classroom.access.role(i) is Role.INSTRUCTOR)
    button = str(form._button._impl.uuid)
    send_to(client, button, "hint", MARK)
    _wait(lambda: last_prop(instructor, button, "hint") == MARK)
    assert set(instructor.updates(choice)[before:]) <= {"module_failure"}


def test_a_pick_the_new_list_lacks_moves_to_its_first(
    faults: tuple[ServedRig, Page, Any],
) -> None:
    """The instructor picked output_short on the DB16's list after the form had the AO4's (the
    page's click before the new list reached it): the form moves it to ao_overload, which the
    module takes, as restrict moves a pick its new list lacks."""
    live, instructor, copy = faults
    form: ActionForm = copy.form
    choice = str(form.choice._impl.uuid)
    instructor.set(str(copy.module._impl.uuid), "5 AO4")
    _wait(lambda: form.options() == AO4 and form._built_for == form.choice.value)
    assert form.choice.value != AO4[0]
    before = len(instructor.updates(choice))
    instructor.set(choice, "output_short")  # not offered any more
    _drawn(live)
    _wait(lambda: form.choice.value == AO4[0], timeout=5)
    _wait(lambda: form._built_for == AO4[0], timeout=5)
    _wait(lambda: AO4[0] in instructor.updates(choice)[before:], timeout=5)
