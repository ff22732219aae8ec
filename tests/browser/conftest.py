"""Fixtures of the browser tests: a live dashboard on a free port, and a Chromium page.

Chromium is Debian's (``/usr/bin/chromium``, installed by the README's test command), never a
Playwright download. Tests that drive it are marked ``@pytest.mark.browser``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers import (
    CHROMIUM,
    VIEWPORT,
    LiveDashboard,
    start_dashboard,
)

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec


@pytest.fixture
def dashboard_for(tmp_path: Path) -> Iterator[Callable[[Rig | str | Path], LiveDashboard]]:
    """``dashboard_for(rig or rig file)``: a running dashboard, stopped after the test."""
    started: list[LiveDashboard] = []

    def start(rig: Rig | str | Path) -> LiveDashboard:
        if not isinstance(rig, Rig):
            rig = build_rig(load_rig_spec(rig), state_dir=tmp_path / "state")
        live = start_dashboard(rig)
        started.append(live)
        return live

    yield start
    for live in started:
        live.stop()


@pytest.fixture
def live(dashboard_for: Callable[[Rig | str | Path], LiveDashboard]) -> LiveDashboard:
    """The dashboard on the default rig (static/rigs/default.toml), flash in a temp dir."""
    return dashboard_for(DEFAULT_RIG)


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} is missing: install Debian's chromium (the README's test "
                    "command does it)")
    from playwright.sync_api import sync_playwright

    from app.screenshots import launch

    with sync_playwright() as pw:
        chromium, remove_home = launch(pw)  # LAUNCH_ARGS, a home of its own
        yield chromium
        chromium.close()
        remove_home()


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    context = browser.new_context(viewport=VIEWPORT, device_scale_factor=1)
    page = context.new_page()
    yield page
    context.close()
