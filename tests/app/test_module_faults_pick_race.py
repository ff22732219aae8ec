"""An instructor's *Module faults* form (app/ui/panels/module_faults.py) offers the fault actions
of the module its own Module picker names on the rail as it is, whichever of its two readers of
the rail comes last: the picker's callback (viser's thread pool) and the frame update of a rail
change (the dashboard thread). Each reads the pick and the rail and parks what the module takes
(nothing for an empty slot; else the model's answer, read in the simulation thread), and the
frame update shows what was parked last.

A pick of the empty slot 3 read the rail, then DO16 was plugged there and the frame update
parked and showed DO16's actions, then the callback parked its "nothing" over them: the form
offered "(none)" for a slot holding a DO16 until the pick or the rail changed again. The test
holds the callback between its read of the rail and its park.
"""

from __future__ import annotations

import threading
from typing import Any

import pytest
from pick_race import HOLD_S, SpyLock, off_dashboard, on_dashboard

from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_classroom_leak import _wait, open_class
from tests.app.test_module_picks_per_browser import _powered_module_3_pulled

AO4 = ("ao_overload", "calibrated", "module_failure")  # the fault actions "5 AO4" takes
DO16 = ("module_failure", "output_short")  # and a DO16


def _drawn_after(live: ServedRig) -> None:
    """A frame update that began after now has ended (a paused rig publishes 30 frames a
    second): it showed what was parked before."""
    seq = live.runtime.frame.seq + 1
    _wait(lambda: live.dashboard.rendered_seq >= seq)


def test_a_pick_read_before_a_rail_change_does_not_park_over_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    with open_class() as (live, _trainee, instructor):
        _powered_module_3_pulled(live)
        faults = live.dashboard._panels.modules._faults  # type: ignore[union-attr]
        copy = _wait(lambda: next((c for c in faults._part.each() if c.form is not None), None))
        module = str(copy.module._impl.uuid)
        _wait(lambda: "3 (empty)" in copy.module.options)
        instructor.set(module, "5 AO4")
        _wait(lambda: copy.form.options() == AO4)
        entered, release, parked = threading.Event(), threading.Event(), threading.Event()
        rail, park = faults._rail, faults._park
        spy = SpyLock(on_dashboard)
        if hasattr(copy, "lock"):  # the form's lock, if it has one
            monkeypatch.setattr(copy, "lock", spy)

        def held_rail() -> Any:
            read = rail()
            if off_dashboard() and not entered.is_set():
                entered.set()  # what the callback read is fixed, its park is to come
                assert release.wait(HOLD_S), "never released"
            return read

        def held_park(*args: Any) -> None:
            park(*args)
            if off_dashboard() and entered.is_set():
                parked.set()

        monkeypatch.setattr(faults, "_rail", held_rail)
        monkeypatch.setattr(faults, "_park", held_park)
        instructor.set(module, "3 (empty)")
        try:
            assert entered.wait(HOLD_S), "the pick's callback did not read the rail"
            live.runtime.command("fastcat/3", "plug", {"type": "DO16"}).result(timeout=10)
            # The frame update showed DO16's actions, or waits for the callback to park first.
            _wait(lambda: copy.form.options() == DO16 or spy.waiting.is_set())
        finally:
            release.set()
        assert parked.wait(HOLD_S), "the pick's callback did not park"
        _drawn_after(live)  # what it parked is shown
        assert copy.module.value == "3 DO16"
        # Nothing asks again before the pick or the rail changes: a stale park stays.
        _wait(lambda: copy.form.options() == DO16, timeout=5)
