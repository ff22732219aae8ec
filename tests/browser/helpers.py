"""Helpers for the headless browser tests: a live dashboard, Chromium, screenshot baselines.

The simulation runs *paused* and advances only when a test says so (:meth:`LiveDashboard.
advance`), so what the page shows at a screenshot is a function of the test's steps, not of
how fast this machine is: LED phases, log timestamps and retries of the master all land on
the same simulated instants every run. Commands from the browser still reach the models at
once (a paused runtime keeps applying queued work).

Screenshots and their baselines: shots.py (re-exported here).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shots import (
    MAX_DIFF_FRACTION,
    close_webgl_toast,
    compare_screenshot,
    diff_fraction,
    quiet_pointer,
    steady_picture,
)

from app import screenshots
from app.rig import Rig
from app.screenshots import CHROMIUM, VIEWPORT, ServedRig, free_port

__all__ = ["CHROMIUM", "MAX_DIFF_FRACTION", "VIEWPORT", "close_webgl_toast",  # for the tests
           "compare_screenshot", "diff_fraction", "free_port", "quiet_pointer", "steady_picture"]
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


def text_input(page: Any, label: str) -> Any:
    """The input of the viser text field ``label`` (viser does not link those labels)."""
    return page.locator(f"xpath=//label[normalize-space(.)='{label}']"
                        "/ancestor::*[.//input][1]//input").first


def choose(page: Any, label: str, option: str) -> None:
    """Pick ``option`` (a prefix of its text is enough) in the viser dropdown ``label``."""
    page.get_by_label(label, exact=True).click()
    page.get_by_role("option", name=option).first.click()
