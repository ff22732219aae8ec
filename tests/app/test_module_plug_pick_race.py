"""The FastCAT's *Plug type* ends on the type the picked empty slot expects (seed 000 §2: a
module pulled and put back; the rail entry's ``expected``), whichever of its two writers comes
last (app/ui/panels/modules.py): a Module pick (viser's thread pool) and the frame update of a
rail change (the dashboard thread), which presets every page's, or an instructor's own, Plug
type again.

Each read the pick and the rail, then wrote the preset, unguarded: a frame update that read the
pick of slot 3 (DO16 expected) before the page picked slot 2 (DI16 expected) wrote DO16 over the
pick's DI16, and Plug put a DO16 in slot 2 (a module the coupler does not expect there). Nothing
put it right before the next rail change: the frame update presets a page only on a rail change
(or a new page), the type picked afterwards staying. The tests hold the frame update between
its read and its write while the page picks.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from pick_race import HOLD_S, SpyLock, off_dashboard, on_dashboard

from app.ui.panels import modules as modules_module
from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_classroom_leak import Page, _wait, open_class
from tests.app.test_module_picks_per_browser import _powered_module_3_pulled
from tests.app.test_picks_per_browser import _ids, _widget
from tests.app.two_pages import two_pages


@pytest.fixture
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages(prepare=_powered_module_3_pulled) as pages:
        yield pages


def _drawn(live: ServedRig) -> None:
    seq = live.runtime.frame.seq
    _wait(lambda: live.dashboard.rendered_seq >= seq)


class _HeldPreset:
    """``plug_preset`` as the dashboard thread sees it: once armed, its next preset of slot 3
    (the rail entry read, the preset worked out, not yet written) waits for ``release``."""

    def __init__(self) -> None:
        self._real = modules_module.plug_preset
        self.armed, self.entered, self.release = False, threading.Event(), threading.Event()

    def __call__(self, entry: Any, catalog: Any) -> str | None:
        preset = self._real(entry, catalog)
        if self.armed and on_dashboard() and entry and entry.get("slot") == 3:
            self.armed = False
            self.entered.set()
            assert self.release.wait(HOLD_S), "never released"
        return preset


def _pick_during_rail_change(live: ServedRig, monkeypatch: pytest.MonkeyPatch, form: Any,
                             preset_name: str, pick: Callable[[], None]) -> None:
    """Unplug module 2, hold that rail change's frame update in ``plug_preset`` of slot 3,
    ``pick`` meanwhile, then let it go; returns once the pick's callback wrote its preset
    (``preset_name``: the modules panel's method that callback runs) and a frame was drawn."""
    modules = live.dashboard._panels.modules  # type: ignore[union-attr]
    held, spy = _HeldPreset(), SpyLock(off_dashboard)
    monkeypatch.setattr(modules_module, "plug_preset", held)
    if hasattr(form, "lock"):  # the form's lock, if it has one
        monkeypatch.setattr(form, "lock", spy)
    written, real = threading.Event(), getattr(modules, preset_name)

    def preset(arg: Any) -> None:
        try:
            real(arg)
        finally:
            if off_dashboard() and held.entered.is_set():
                written.set()

    monkeypatch.setattr(modules, preset_name, preset)
    _drawn(live)  # no update under way: the next is the rail change's
    held.armed = True
    try:
        live.runtime.command("fastcat/2", "unplug", {}).result(timeout=10)
        assert held.entered.wait(HOLD_S), "the rail change's frame update did not preset"
        pick()
        # The pick's callback has written, or waits for the frame update to write first.
        _wait(lambda: written.is_set() or spy.waiting.is_set())
    finally:
        held.release.set()
    assert written.wait(HOLD_S), "the pick's callback did not finish"
    _drawn(live)


def test_a_pick_during_a_rail_change_frame_keeps_its_slot_s_preset(
    served: tuple[ServedRig, Page, Page],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An open rig: module 2 is pulled while page A has picked the empty slot 3; the frame
    update of that rail change read A's pick (slot 3: DO16), then A picked slot 2 (DI16) and
    its callback wrote DI16, then the frame update wrote DO16 over it."""
    live, first, _second = served
    modules = live.dashboard._panels.modules  # type: ignore[union-attr]
    shared = modules._shared_rail
    one, _two = _ids(live)
    picker = _widget(first, "Module", "3 (empty)")
    plug_type = _widget(first, "Plug type", "DO16")
    first.set(picker, "3 (empty)")
    _wait(lambda: shared.plug_type.value_for(one) == "DO16")
    _pick_during_rail_change(live, monkeypatch, shared, "_preset_page",
                             lambda: first.set(picker, "2 (empty)"))
    assert modules.pick.value_for(one) == "2 (empty)"
    # No later frame presets the page again before the next rail change: a stale preset
    # stays, and these time out.
    _wait(lambda: shared.plug_type.value_for(one) == "DI16", timeout=5)
    _wait(lambda: (first.updates(plug_type) or [None])[-1] == "DI16", timeout=5)


def test_an_instructor_s_pick_during_a_rail_change_frame_keeps_its_slot_s_preset(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With a token the Rail rows are each instructor's own, with their own Module picker
    (docs/classroom.md): the frame update of a rail change read the picker's slot 3 (DO16),
    the instructor picked slot 2 (DI16) and its callback wrote DI16, then the frame update
    wrote DO16 over it."""
    with open_class() as (live, _trainee, instructor):
        _powered_module_3_pulled(live)
        modules = live.dashboard._panels.modules  # type: ignore[union-attr]
        form = _wait(lambda: (modules._rails.each() or [None])[0])
        module = str(form.module._impl.uuid)
        _wait(lambda: "3 (empty)" in form.module.options)
        instructor.set(module, "3 (empty)")
        _wait(lambda: form.plug_type.value == "DO16")
        _pick_during_rail_change(live, monkeypatch, form, "_preset",
                                 lambda: instructor.set(module, "2 (empty)"))
        assert form.module.value == "2 (empty)"
        # No later frame presets the rows again before the next rail change.
        _wait(lambda: form.plug_type.value == "DI16", timeout=5)
