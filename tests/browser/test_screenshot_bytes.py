"""A picture of `--screenshots` depends on the rig's state only, not on what the page drew
before: byte for byte (docs/scenarios.md "Screenshots for CI").

Run twice, the examples gave different PNG bytes (0 to 40 pixels a picture, 1 to 5 grey
levels): the page draws whatever frames it gets while the paused rig is stepped to the next
checkpoint, a number that depends on the machine's load, and two things kept traces of them:

- viser's 3D label glyph atlas (app/ui/glyphs.py): glyphs packed in the order labels first
  showed them, so label text sampled differently;
- Chromium's partial raster and GPU raster (app/screenshots.py LAUNCH_ARGS): rounded corners
  and icons of the panels re-rastered over an earlier frame's tile, and a uPlot canvas
  flushed after the capture.

The first test draws one page through a history (other label texts first) and one straight
to the same state; the second runs a scenario twice. Both want the same bytes.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario
from app.screenshots import (
    Chromium,
    DashboardPage,
    ServedRig,
    run_with_screenshots,
    served_run,
)
from app.ui.glyphs import BASE_GLYPHS, WARM_SCALES

pytestmark = pytest.mark.browser

History = Callable[[ServedRig, DashboardPage], None]


def every_glyph_in_lines(width: int = 48) -> str:
    return "\n".join(BASE_GLYPHS[i:i + width] for i in range(0, len(BASE_GLYPHS), width))


def picture(out: Path, history: History, to_s: float) -> bytes:
    """The default rig served, a page opened, ``history`` played, then the rig advanced to
    ``to_s`` simulated seconds, labels of every glyph put in the middle of the view (text
    whose glyphs were packed after the history's) and photographed."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    with served_run(rig, quiet=True) as (served, _events), Chromium() as browser:
        page = browser.open(served)
        served.command("fastcat", "power", {"on": True})
        history(served, page)
        rest = to_s - served.runtime.rig.clock.now_us / 1e6
        if rest > 0:
            served.advance(rest)
        middle = served.server.initial_camera.look_at
        for i, scale in enumerate(WARM_SCALES):
            served.server.scene.add_label(f"/every_glyph{i}", every_glyph_in_lines(),
                                          position=middle, anchor="center-center",
                                          font_screen_scale=scale)
        served.advance(0.1)
        page.screenshot(out)
        page.close()
    return out.read_bytes()


def two_pictures(tmp_path: Path, history: History, to_s: float) -> tuple[bytes, bytes]:
    def run() -> tuple[bytes, bytes]:
        return (picture(tmp_path / "straight.png", lambda _s, _p: None, to_s),
                picture(tmp_path / "history.png", history, to_s))

    with ThreadPoolExecutor(1) as pool:  # a Playwright of its own (test_screenshots_cli.py)
        return pool.submit(run).result(timeout=600)


def other_glyphs_first(served: ServedRig, page: DashboardPage) -> None:
    """Labels showing every glyph in reverse order before the rail's texts change: what a
    page drawing other intermediate texts (a position counting, another caption) does."""
    probes = [served.server.scene.add_label(f"/probe{i}", BASE_GLYPHS[::-1],
                                            font_screen_scale=scale)
              for i, scale in enumerate(WARM_SCALES)]
    served.advance(0.1)
    page.sync()
    for probe in probes:
        probe.remove()


def test_label_text_is_the_same_whatever_labels_showed_before(tmp_path: Path) -> None:
    straight, history = two_pictures(tmp_path, other_glyphs_first, 4.0)
    assert straight == history


def test_two_runs_of_a_drive_scenario_give_the_same_bytes(tmp_path: Path) -> None:
    """The Drive tab's plots (uPlot canvases), the scrollbars and the player folder's
    corners and chevron differed by 1 to 5 grey levels in 7 of 9 pairs of runs of this
    scenario, each pair in at least one picture, until the page was rastered on the CPU
    without partial raster (app/screenshots.py LAUNCH_ARGS)."""
    scenario = load_scenario(DEFAULT_RIG.parent.parent / "scenarios"
                             / "canopen_drive_alarm_reset.toml")

    def run(out: Path) -> list[bytes]:
        with ThreadPoolExecutor(1) as pool:  # a Playwright of its own
            shot = pool.submit(run_with_screenshots, scenario,
                               build_rig(load_rig_spec(DEFAULT_RIG)), out, quiet=True)
            images = shot.result(timeout=600).images
        assert [p.name for p in images] == ["01-overtemperature.png", "02-reset.png"]
        return [p.read_bytes() for p in images]

    assert run(tmp_path / "a") == run(tmp_path / "b")
