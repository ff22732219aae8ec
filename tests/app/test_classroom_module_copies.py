"""An instructor's own Module pickers (the FastCAT tab's Module faults and Rail and power)
follow the rail whenever they were built (docs/classroom.md "What a trainee does not see").
Before, a copy was brought up to date on the frame the rail changed only, for the copies there
were then: a copy built from the rail before that frame and stored after it (the promote runs on
another thread than the dashboard's update) kept the old options until the rail changed again.
On a loaded machine the instructor's pickers then offered no "4 AI8D" on a freshly numbered rail
(test_classroom_leak's Page.own waited 20 s for it and failed)."""

from __future__ import annotations

from typing import Any

import pytest
from test_classroom_leak import TOKEN, Page, _wait

from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.panels.classroom_rig import serve_rig
from app.ui.panels.control import module_options


@pytest.mark.parametrize("which", ["faults", "rails"])
def test_a_copy_built_during_a_rail_change_gets_the_new_rail(which: str) -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    page = None
    try:
        dashboard = served.dashboard
        dashboard.tick()
        assert dashboard._panels is not None
        modules = dashboard._panels.modules
        assert modules._faults is not None
        assert "3 DO16" in module_options(modules._rail)
        page = Page(served.port)
        cid, client = next(iter(_wait(lambda: served.server.get_clients()).items()))
        assert served.classroom.access.present(cid, TOKEN)
        with dashboard.held():  # no update of the dashboard's own meanwhile
            served.runtime.command("fastcat/3", "unplug", {}).result(timeout=10)
            served.runtime.advance(100_000).result(timeout=30)
            fastcat = dict(served.runtime.frame.snapshot["devices"]["fastcat"])
            new = module_options(fastcat["rail"])
            assert "3 (empty)" in new
            # The parts are built in turn: the frame comes during the build of ``which``.
            part = modules._faults._part if which == "faults" else modules._rails
            build = part._build

            def build_then_update(gui: Any) -> Any:
                built = build(gui)  # from the rail as it was
                modules.update(fastcat)  # the frame that brings the new rail
                return built

            part._build = build_then_update  # type: ignore[method-assign]
            served.dashboard.instructor.promote(client)
            modules.update(fastcat)  # the next frame: the rail as it is now
            (faults,) = modules._faults._part.each()
            (rails,) = modules._rails.each()
            assert list(faults.module.options) == new
            assert list(rails.module.options) == new
            assert list(rails.swap_with.options) == new
    finally:
        if page is not None:
            page.close()
        served.stop()
