"""The FastCAT's *Plug type* preset follows the type the picked empty slot expects (seed 000 §2:
the rail entry's ``expected``, flash else the last scan) when only that changes: a CNF (§2: the
configuration stored anew) with the rail as it was. Before, the frame update presetted again
only when a slot's type, slot or encoders changed: after a CNF with module 3 pulled, flash
made slot 3's module the AI8D, the box kept offering the DO16 of the last scan, and Plug put
a DO16 where the coupler now expects an AI8D, until an unrelated rail change
(app/ui/panels/modules.py, ``ModulePanel.update``).
"""

from __future__ import annotations

from typing import Any

from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_classroom_leak import _wait, open_class
from tests.app.test_module_picks_per_browser import _powered_module_3_pulled, _rail
from tests.app.test_picks_per_browser import _ids, _widget
from tests.app.two_pages import two_pages


def _store_with_slot_3_empty(live: ServedRig) -> list[Any]:
    """CNF held 3.5 s (§2), then the reset, the scan and the store: the rail is as it was,
    slot 3's ``expected`` goes from the last scan's DO16 to flash's module 3, the AI8D."""
    before = _rail(live)
    assert before[2]["type"] is None and before[2]["expected"] == "DO16"
    live.runtime.command("fastcat", "hold_cnf", {"seconds": 3.5}).result(timeout=10)
    live.runtime.advance(8_000_000).result(timeout=60)
    after = _rail(live)
    assert after[2]["expected"] == "AI8D" and after[2]["expected_from"] == "flash"
    key = [(e["slot"], e["type"], e.get("encoders") is not None) for e in before]
    assert [(e["slot"], e["type"], e.get("encoders") is not None) for e in after] == key
    return after


def test_an_open_rig_s_page_follows_a_new_expected_type() -> None:
    with two_pages(prepare=_powered_module_3_pulled) as (live, first, _second):
        modules = live.dashboard._panels.modules  # type: ignore[union-attr]
        shared = modules._shared_rail
        one, _two = _ids(live)
        picker = _widget(first, "Module", "3 (empty)")
        plug_type = _widget(first, "Plug type", "DO16")
        first.set(picker, "3 (empty)")
        _wait(lambda: shared.plug_type.value_for(one) == "DO16")
        _store_with_slot_3_empty(live)
        _wait(lambda: shared.plug_type.value_for(one) == "AI8D", timeout=5)
        _wait(lambda: (first.updates(plug_type) or [None])[-1] == "AI8D", timeout=5)


def test_an_instructor_s_own_rows_follow_a_new_expected_type() -> None:
    with open_class() as (live, _trainee, instructor):
        _powered_module_3_pulled(live)
        modules = live.dashboard._panels.modules  # type: ignore[union-attr]
        form = _wait(lambda: (modules._rails.each() or [None])[0])
        _wait(lambda: "3 (empty)" in form.module.options)
        instructor.set(str(form.module._impl.uuid), "3 (empty)")
        _wait(lambda: form.plug_type.value == "DO16")
        _store_with_slot_3_empty(live)
        _wait(lambda: form.plug_type.value == "AI8D", timeout=5)
