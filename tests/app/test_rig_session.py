"""app.testing's RigSession: after advance() or command() the dashboard shows the rig as it
stands, so a test may read the views at once (tests/app/test_log_repeats.py reads the State
tab's event log). Before, both returned as soon as the simulation thread had run the step; the
dashboard's thread drew that frame, and took the step's events, a moment later: on a loaded CI
machine the event log was read before its last rows were there.
"""

from __future__ import annotations

from collections.abc import Callable

from app.testing import rig_session


def test_the_dashboard_has_drawn_each_step_and_command_when_they_return() -> None:
    with rig_session() as rig:
        dashboard, runtime = rig.served.dashboard, rig.served.runtime
        # A paused runtime keeps publishing frames (30 Hz): the frame published by the time
        # the assertion reads it may be newer than the one drawn, so each call is checked
        # against the frame before it: one published after its step has been drawn.
        def drawn_after(call: Callable[[], object]) -> None:
            before = runtime.frame.seq
            call()
            assert dashboard.rendered_seq > before

        drawn_after(lambda: rig.command("fastcat", "power", on=True))
        for _ in range(6):
            drawn_after(lambda: rig.advance(0.5))
        drawn_after(lambda: rig.command("fastcat/2", "unplug"))
        drawn_after(lambda: rig.advance(0.1))
        panels = dashboard._panels
        assert panels is not None
        # Seed 000 §7: module 2 gone in OP, the coupler's emergency; the step's event is in
        # the log the dashboard drew.
        assert "Emergency sent (code 0xFF00" in str(panels.log._html.content)
