"""Helpers for the headless browser tests: a live dashboard, Chromium, screenshot baselines.

The simulation runs *paused* and advances only when a test says so (:meth:`LiveDashboard.
advance`), so what the page shows at a screenshot is a function of the test's steps, not of
how fast this machine is: LED phases, log timestamps and retries of the master all land on
the same simulated instants every run. Commands from the browser still reach the models at
once (a paused runtime keeps applying queued work).

Screenshots are compared with committed baselines under ``baselines/`` with a tolerance
(software WebGL anti-aliasing may differ slightly between Chromium builds). On a mismatch the
actual image and a diff image go to ``output/``; ``FIELDRIG_UPDATE_BASELINES=1`` rewrites the
baselines instead of comparing.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

from PIL import Image, ImageChops

from app import screenshots
from app.rig import Rig
from app.screenshots import CHROMIUM, VIEWPORT, ServedRig, free_port

__all__ = ["CHROMIUM", "VIEWPORT", "free_port"]  # re-exported for the tests
HERE = Path(__file__).resolve().parent
BASELINES = HERE / "baselines"
OUTPUT = HERE / "output"
UPDATE_ENV = "FIELDRIG_UPDATE_BASELINES"

PIXEL_THRESHOLD = 40  # a channel difference above this makes a pixel "different"
# Share of different pixels allowed. Runs on one machine differ by 0 % (fixed DPR, paused
# simulation); a moved label or a changed text line is 0.3-1.5 %. viser's own e2e: 2 %.
MAX_DIFF_FRACTION = 0.01
WALL_TIMEOUT_S = 20.0


def wait_until(predicate: Callable[[], Any], timeout: float = WALL_TIMEOUT_S,
               what: str = "condition") -> Any:
    """Poll ``predicate`` (wall time: browser round trips are real time) until truthy."""
    return screenshots.wait_until(predicate, what, timeout)


class LiveDashboard(ServedRig):
    """The screenshot CLI's served rig, with what the tests wait for."""

    @property
    def rig(self) -> Rig:
        return self.runtime.rig

    def snapshot(self, device: str = "fastcat") -> dict[str, Any]:
        return self.runtime.frame.snapshot["devices"][device]

    def advance(self, seconds: float) -> None:
        """Step the paused simulation by exactly ``seconds``, in the simulation thread, with
        the events journalled as the running runtime would, then let the view catch up."""
        self.runtime.advance(round(seconds * 1_000_000)).result(timeout=WALL_TIMEOUT_S * 3)
        self.settle()

    def wait_for_state(self, predicate: Callable[[dict[str, Any]], Any],
                       what: str = "device state") -> None:
        """Wait for a browser command to reach the model (the simulation is paused)."""
        wait_until(lambda: predicate(self.snapshot()), what=what)
        self.settle()


def start_dashboard(rig: Rig) -> LiveDashboard:
    live = LiveDashboard.start(rig)
    live.settle()
    return live


# ---- the page ----------------------------------------------------------------------------
def close_webgl_toast(page: Any, timeout: float = 15.0) -> None:
    """viser's "Software WebGL rendering detected" notice never closes by itself."""
    toast = page.locator(".mantine-Notification-root", has_text="Software WebGL")
    toast.first.wait_for(timeout=timeout * 1000)
    toast.first.locator("button").click()
    toast.first.wait_for(state="detached", timeout=timeout * 1000)


def open_dashboard(page: Any, live: LiveDashboard) -> None:
    # viser lowers the canvas resolution when software WebGL renders slowly, which moves
    # pixels between runs; viser's own fixedDpr parameter pins it (docs/dashboard.md).
    page.goto(f"{live.url}/?fixedDpr=1")
    wait_for_text(page, "ESM state")
    close_webgl_toast(page)


def wait_for_text(page: Any, text: str, timeout: float = WALL_TIMEOUT_S) -> None:
    page.get_by_text(text, exact=False).first.wait_for(timeout=timeout * 1000)


def state_value(page: Any, row: str) -> str:
    """A value of the state panel, as the page shows it (``row`` = the left column)."""
    cell = page.locator("#fr-state tr", has=page.locator("th", has_text=row)).locator("td")
    return str(cell.first.inner_text()).strip()


def log_text(page: Any) -> str:
    return str(page.locator("#fr-log").inner_text())


def quiet_pointer(page: Any) -> None:
    """Park the mouse on the title bar: no hover outline or tooltip in a screenshot."""
    page.mouse.move(640, 12)
    page.wait_for_timeout(700)  # tooltips have a 500 ms delay; let any one close


def text_input(page: Any, label: str) -> Any:
    """The input of the viser text field ``label`` (viser does not link those labels)."""
    return page.locator(f"xpath=//label[normalize-space(.)='{label}']"
                        "/ancestor::*[.//input][1]//input").first


def choose(page: Any, label: str, option: str) -> None:
    """Pick ``option`` (a prefix of its text is enough) in the viser dropdown ``label``."""
    page.get_by_label(label, exact=True).click()
    page.get_by_role("option", name=option).first.click()


# ---- screenshots -------------------------------------------------------------------------
SHIFTS = [(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1)]


def diff_fraction(actual: Image.Image, expected: Image.Image,
                  threshold: int = PIXEL_THRESHOLD) -> tuple[float, Image.Image]:
    """Share of pixels that differ, and the mask. A pixel differs when its largest channel
    difference exceeds ``threshold`` against each pixel of the baseline's 3x3 neighbourhood:
    the 3D view's framing can land one pixel off under load (CI saw the whole scene shifted
    by 1 px: 1.03 % of the pixels, all on edges), while a changed LED, label or text still
    differs from every neighbour."""
    actual, expected = actual.convert("RGB"), expected.convert("RGB")
    mask = None
    for dx, dy in SHIFTS:
        diff = ImageChops.difference(actual, ImageChops.offset(expected, dx, dy))
        red, green, blue = diff.split()
        worst = ImageChops.lighter(ImageChops.lighter(red, green), blue)
        mask = worst if mask is None else ImageChops.darker(mask, worst)
    mask = mask.point(lambda v: 255 if v > threshold else 0)
    return mask.histogram()[255] / (mask.width * mask.height), mask


def compare_screenshot(page: Any, name: str,
                       max_fraction: float = MAX_DIFF_FRACTION) -> Path:
    """Screenshot the page and compare it with ``baselines/<name>.png``."""
    quiet_pointer(page)
    OUTPUT.mkdir(parents=True, exist_ok=True)
    actual_path = OUTPUT / f"{name}.png"
    page.screenshot(path=str(actual_path))
    baseline = BASELINES / f"{name}.png"
    if os.environ.get(UPDATE_ENV) == "1":
        BASELINES.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(actual_path, baseline)
        return baseline
    assert baseline.exists(), (f"no baseline {baseline.relative_to(HERE.parents[1])}: run "
                               f"with {UPDATE_ENV}=1 to create it, then look at it")
    actual, expected = Image.open(actual_path), Image.open(baseline)
    assert actual.size == expected.size, f"{name}: size {actual.size} != {expected.size}"
    fraction, mask = diff_fraction(actual, expected)
    if fraction > max_fraction:
        highlight = Image.composite(Image.new("RGB", actual.size, (255, 0, 0)),
                                    actual.convert("RGB").point(lambda v: v // 3), mask)
        highlight.save(OUTPUT / f"{name}.diff.png")
        raise AssertionError(f"{name}: {fraction:.2%} of the pixels differ from the baseline "
                             f"(allowed {max_fraction:.2%}); see {OUTPUT / (name + '.png')} "
                             f"and {name}.diff.png")
    return actual_path
