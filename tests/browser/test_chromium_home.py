"""Headless Chromium (``--screenshots``, app/testing.py, the browser fixture, the browser
benchmarks' ``bench._browser.chromium``) writes nothing
into the user's home: a CI run with screenshots left ``~/.config/chromium/Crash Reports`` and
``~/.cache/dconf`` behind. It gets a home of its own, removed when it closes."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from app.screenshots import LAUNCH_ARGS, Chromium
from bench._browser import chromium as bench_chromium

pytestmark = pytest.mark.browser


def _browse_with_cli_chromium() -> None:
    with Chromium() as chromium:
        _draw(chromium.browser)


def _browse_with_bench_chromium() -> None:
    with bench_chromium() as browser:
        _draw(browser)


def _draw(browser: Any) -> None:
    page = browser.new_page()
    page.set_content("<canvas id=c></canvas><script>"
                     "document.getElementById('c').getContext('webgl')</script>")
    page.close()


@pytest.mark.parametrize("browse", [_browse_with_cli_chromium, _browse_with_bench_chromium],
                         ids=["screenshots", "bench"])
def test_chromium_leaves_home_alone_and_cleans_up(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch,
                                                  browse: Callable[[], None]) -> None:
    home, temp = tmp_path / "home", tmp_path / "tmp"
    home.mkdir()
    temp.mkdir()
    monkeypatch.setenv("HOME", str(home))
    for name in ("XDG_CONFIG_HOME", "XDG_CACHE_HOME", "XDG_DATA_HOME"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(tempfile, "tempdir", str(temp))  # where the private home goes

    # A thread of its own: Playwright's sync API does not start twice in one thread (the
    # session's browser fixture).
    with ThreadPoolExecutor(1) as pool:
        pool.submit(browse).result(timeout=120)
    assert sorted(str(p.relative_to(home)) for p in home.rglob("*")) == []
    assert list(temp.iterdir()) == []
    assert "--disable-crash-reporter" in LAUNCH_ARGS
