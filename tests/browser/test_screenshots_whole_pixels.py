"""The `--screenshots` pictures have the 3D canvas on whole CSS pixels (docs/scenarios.md
"Screenshots for CI").

viser's title bar is 47.36 px high, so the 3D canvas under it was 672.64 CSS px high over a
672 px drawing buffer, and Chromium sometimes drew that buffer stretched over the fraction
(docs/dashboard.md "Browser tests"). Here the CLI's own path (``run_with_screenshots``) runs
a scenario and the page is measured right after each picture it takes: nothing moves the
paused page between the picture and the measure.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from app import screenshots
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario

pytestmark = pytest.mark.browser

SCENARIO = DEFAULT_RIG.parent.parent / "scenarios" / "module_lost_in_op.toml"
# Measured on its own (not with the app's pinning code): the canvas of the largest drawing
# buffer, the 3D view (an empty 0 x 0 canvas of viser's lies over it with the same box)
CANVAS_GEOMETRY_JS = """() => {
  const area = c => c.width * c.height;
  const canvas = [...document.querySelectorAll('canvas')].reduce(
    (big, c) => (big === null || area(c) > area(big) ? c : big), null);
  if (canvas === null) return null;
  const box = canvas.getBoundingClientRect();
  return {top: box.top, left: box.left, width: box.width, height: box.height,
          bufferWidth: canvas.width, bufferHeight: canvas.height,
          dpr: window.devicePixelRatio};
}"""


def geometry_at_each_picture(out: Path, monkeypatch: pytest.MonkeyPatch) -> list[dict[str, Any]]:
    seen: list[dict[str, Any]] = []
    shoot = screenshots._shoot

    def measured(page: screenshots.DashboardPage, *args: Any) -> Path:
        path = shoot(page, *args)
        seen.append(page.page.evaluate(CANVAS_GEOMETRY_JS))
        return path

    monkeypatch.setattr(screenshots, "_shoot", measured)
    run = screenshots.run_with_screenshots(load_scenario(SCENARIO),
                                           build_rig(load_rig_spec(DEFAULT_RIG)), out,
                                           quiet=True)
    assert not run.failures and len(run.images) == len(seen) == 3
    return seen


def test_each_picture_has_the_3d_canvas_on_whole_pixels(tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    with ThreadPoolExecutor(1) as pool:  # a Playwright of its own (test_screenshots_cli.py)
        seen = pool.submit(geometry_at_each_picture, tmp_path, monkeypatch).result(timeout=600)
    for geometry in seen:
        assert geometry is not None, "no canvas on the page"
        assert geometry["dpr"] == 1
        # the title bar above it is 47 px, not viser's 47.36 px: the box starts on a pixel
        assert float(geometry["top"]).is_integer(), geometry
        assert float(geometry["height"]).is_integer(), geometry
        assert geometry["height"] == geometry["bufferHeight"], geometry
        assert geometry["width"] == geometry["bufferWidth"], geometry
