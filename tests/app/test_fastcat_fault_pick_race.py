"""An open rig's Faults form ends with each page's Target on one its own code takes
(seed 000 §7.5: 0x10-0x13 name no node, the coupler only; §7.6: a module code names a
module), whichever of its two writers comes last (app/ui/panels/control.py ``_show_faults``):
a page's pick of a Table or Fault (viser's thread pool) and the dashboard's frame update (its
own thread).

The frame update worked out each page's targets from its code, wrote them, then moved each
page's Target that its list did not hold, unguarded: a page's pick of the module Table in
between (its code now a module code, its Target moved by its callback to a module) was moved
back to the coupler by the list worked out before, a target its code does not take. The page
kept it until the next frame: 1/30 s on an idle rig, as long as a busy simulation thread takes
otherwise. The test holds the frame update between its write of the lists and its moves, with
no frame to put it right.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest
from pick_race import HOLD_S, HeldProp, SpyLock, off_dashboard, on_dashboard
from test_slave_causes_pick_race import _NoFrames

from app.classroom.roles import Role
from app.ui.panels import control as control_module
from app.ui.panels.classroom_rig import ServedRig
from app.ui.panels.control import COUPLER_TARGET, TABLE_LABELS, fault_targets
from devices.fastcat.alarms import COUPLER_CODES
from tests.app.test_classroom_leak import Page, _wait, open_class
from tests.app.test_fastcat_fault_targets_per_page import _offered
from tests.app.test_picks_per_browser import _ids, _widget
from tests.app.two_pages import powered, two_pages

NO_NODE = f"0x10 {COUPLER_CODES[0x10].symbol}"  # §7.5: about no node, the coupler only
MISSING = f"0x04 {COUPLER_CODES[0x04].symbol}"  # §7.5: the coupler and the modules


@pytest.fixture
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages(prepare=powered) as pages:
        yield pages


def _rail(live: ServedRig) -> tuple[str, ...]:
    rail = live.runtime.submit(
        lambda: live.rig.device("fastcat").snapshot()["rail"]).result(timeout=10)
    return tuple(fault_targets(rail))


def _drawn(live: ServedRig) -> None:
    seq = live.runtime.frame.seq
    _wait(lambda: live.dashboard.rendered_seq >= seq)


def test_a_pick_during_a_frame_update_is_not_undone_by_it(
    served: tuple[ServedRig, Page, Page],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The frame update worked out page A's targets for its coupler-only code and wrote them;
    A picked the module Table (its code: the table's first, a module code) and its callback
    moved A's Target to a module; then the frame update moved it back to the coupler."""
    live, first, _second = served
    control = live.dashboard._panels.control  # type: ignore[union-attr]
    one, _two = _ids(live)
    target = _widget(first, "Target", COUPLER_TARGET)
    modules = _rail(live)
    first.set(_widget(first, "Fault", NO_NODE), NO_NODE)
    _wait(lambda: control._fault.value_for(one) == NO_NODE)
    _wait(lambda: _offered(first, target) == (COUPLER_TARGET,))
    assert control._target.value_for(one) == COUPLER_TARGET
    held = HeldProp(control._target_options, on_dashboard, after=True)
    spy = SpyLock(off_dashboard)
    monkeypatch.setattr(control, "_target_options", held)
    monkeypatch.setattr(control, "_faults_lock", spy, raising=False)  # if it has one
    written, shown = threading.Event(), control._show_faults

    def show(form: object) -> None:
        try:
            shown(form)
        finally:
            if off_dashboard() and held.entered.is_set():
                written.set()

    monkeypatch.setattr(control, "_show_faults", show)
    frames = _NoFrames(live)
    try:
        _drawn(live)  # no update under way: the next is the one of the frame below
        held.armed = True
        try:
            frames.publish()
            assert held.entered.wait(HOLD_S), "the frame update did not write the targets"
            first.set(_widget(first, "Table", TABLE_LABELS["module"]), TABLE_LABELS["module"])
            # The pick's callback has written, or waits for the frame update to end first.
            assert _wait(lambda: written.is_set() or spy.waiting.is_set())
        finally:
            held.release.set()
        assert written.wait(HOLD_S), "the pick's callback did not finish"
        _drawn(live)
        # No frame comes to put it right: a stale move stays, and this times out.
        _wait(lambda: control._target.value_for(one) in modules, timeout=5)
        _wait(lambda: held.sent(one) == modules, timeout=5)
        _wait(lambda: (first.updates(target) or [None])[-1] in modules, timeout=5)
        _wait(lambda: _offered(first, target) == modules, timeout=5)
    finally:
        frames.end()


def test_an_instructor_s_pick_during_a_rail_change_is_not_written_over_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With a token the Faults form is each instructor connection's own (docs/classroom.md),
    its Target list worked out from the rail by its Fault's pick and by each frame: the pick's
    callback read the rail before module 3 was taken off, the frame update wrote the rail
    without it, then the callback wrote the list with module 3 over it."""
    with open_class() as (live, _trainee, instructor):
        control = live.dashboard._panels.control  # type: ignore[union-attr]
        client_id = next(c for c in live.server.get_clients()
                         if live.classroom.access.role(c) is Role.INSTRUCTOR)
        form = _wait(lambda: control._forms.of(client_id))
        before = _rail(live)
        _wait(lambda: tuple(form.target.options) == (COUPLER_TARGET, *before))
        entered, release, written = threading.Event(), threading.Event(), threading.Event()
        taken, offer = control_module.taken_targets, control._offer_targets
        spy = SpyLock(on_dashboard)
        monkeypatch.setattr(control, "_faults_lock", spy, raising=False)  # if it has one

        def held(fault: object, modules: object) -> list[str]:
            if off_dashboard() and not entered.is_set():
                entered.set()  # what the callback read is fixed, its write is to come
                assert release.wait(HOLD_S), "never released"
            return taken(fault, modules)  # type: ignore[arg-type]

        def offered(each: object) -> None:
            try:
                offer(each)
            finally:
                if off_dashboard() and entered.is_set():
                    written.set()

        monkeypatch.setattr(control_module, "taken_targets", held)
        monkeypatch.setattr(control, "_offer_targets", offered)
        frames = None
        instructor.set(str(form.fault._impl.uuid), MISSING)
        try:
            assert entered.wait(HOLD_S), "the pick's callback did not run"
            live.runtime.command("fastcat/3", "unplug", {}).result(timeout=10)
            after = _rail(live)
            assert after != before
            frames = _NoFrames(live)
            frames.publish()
            seq = live.runtime.frame.seq
            # The frame update has written, or waits for the callback to write first.
            _wait(lambda: spy.waiting.is_set() or live.dashboard.rendered_seq >= seq)
        finally:
            release.set()
        try:
            assert written.wait(HOLD_S), "the pick's callback did not finish"
            _drawn(live)
            # No frame comes to put it right: a stale list stays, and this times out.
            _wait(lambda: tuple(form.target.options) == (COUPLER_TARGET, *after), timeout=5)
        finally:
            if frames is not None:
                frames.end()
