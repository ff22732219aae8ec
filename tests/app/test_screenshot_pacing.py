"""What a screenshot run's page is sent must not hang on wall time (docs/scenarios.md
"Screenshots for CI"). Two runs of canopen_drive_alarm_reset differed in the Drive tab's
"Following error" chart grid: whether the default drive's charts got samples before the
focus step picked drive_co hung on whether the dashboard thread drew the frame of the
first step's instant before or after that step's focus event was journalled, and the
charts were sent every SEND_PERIOD_S of wall time, not with the frames.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

import pytest
from served_dashboard import drawn, served_default_rig

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import load_scenario
from app.screenshots import ScreenshotError, ServedRig, play, wait_until
from app.ui.drive import plots as plots_module

SCENARIO = DEFAULT_RIG.parent.parent / "scenarios" / "canopen_drive_alarm_reset.toml"


@pytest.fixture
def served() -> Iterator[ServedRig]:
    with served_default_rig(1.0) as live:
        yield live


def test_the_plots_hold_the_samples_of_every_drawn_frame(served: ServedRig) -> None:
    plots = served.dashboard.drives.plots  # type: ignore[union-attr]
    for _ in range(3):  # well within SEND_PERIOD_S of each other
        served.advance(0.1)
        drawn(served)
        assert plots.caught_up()


def test_a_step_s_frame_is_drawn_with_the_step_s_events(monkeypatch: pytest.MonkeyPatch
                                                        ) -> None:
    """Every frame the simulation publishes is given the dashboard thread's chance to draw
    it at once, and the charts may be sent at any tick (a loaded machine's timing may do
    both): the frame of the focus step's instant must still be drawn with the focus, so the
    default drive's charts never get samples."""
    monkeypatch.setattr(plots_module, "SEND_PERIOD_S", 0.0)
    publish = Runtime._publish
    playing: list[ServedRig] = []

    def eager(runtime: Runtime) -> None:
        publish(runtime)
        if playing:
            live = playing[0]
            seq = runtime.frame.seq
            with contextlib.suppress(ScreenshotError):  # held off: a step not over yet
                wait_until(lambda: live.dashboard.rendered_seq >= seq, "a draw", timeout=0.3)

    monkeypatch.setattr(Runtime, "_publish", eager)
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    live = ServedRig.start(rig, quiet=True)
    try:
        playing.append(live)
        assert play(live, load_scenario(SCENARIO), rig, lambda _step: None) == []
        drives: Any = live.dashboard.drives
        assert drives.selected == "drive_co"
        assert drives._plots["drive"].drawn_points() == 0
        assert drives.plots.caught_up()
    finally:
        playing.clear()
        live.stop()

