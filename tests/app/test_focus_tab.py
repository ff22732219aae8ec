"""A scenario's focus step opens the focused device's tab of the left panel (app/ui/tab_switch.py,
docs/dashboard.md "Focus"); the browser side is tests/browser/test_focus_tabs.py."""

from __future__ import annotations

import html
from collections.abc import Iterator

import pytest
from served_dashboard import ticked_dashboard

from app.ui.dashboard import Dashboard
from app.ui.tab_switch import snippet
from devices.events import Focus


@pytest.fixture(scope="module")
def dashboard() -> Iterator[Dashboard]:
    with ticked_dashboard() as dashboard:
        yield dashboard


@pytest.mark.parametrize(("device", "tab"), [
    ("master", "Line"), ("fastcat", "State"), ("trscat", "Slave"), ("cpx", "Slave"),
    ("drive_ec-ecat", "Slave"), ("drive", "Drive"), ("drive_co", "Drive"),
    ("drive_ec", "Drive"), ("drive-can", None)])
def test_each_device_has_its_tab(dashboard: Dashboard, device: str, tab: str | None) -> None:
    assert dashboard.focus_tab(device) == tab
    if tab is not None:  # a tab the left panel has
        assert tab in [h._label for h in dashboard._side._tab_handles]


def test_a_scenario_focus_opens_the_tab_and_picks_the_drive(
        dashboard: Dashboard, monkeypatch: pytest.MonkeyPatch) -> None:
    opened: list[str] = []
    monkeypatch.setattr(dashboard._tabs, "open", opened.append)
    drives = dashboard._drives
    assert drives is not None
    for target in ("cpx:2", "master", "drive_co", "fastcat/3"):
        dashboard.runtime._journal_events([Focus(0, "scenario", target=target)])
        dashboard.tick()
    assert opened == ["Slave", "Line", "Drive", "State"]
    assert drives.selected == "drive_co"


def test_the_snippet_quotes_its_label() -> None:
    text = html.unescape(snippet('a "b" <c>', 7))
    assert 'var L="a \\"b\\" <c>";' in text and 'data-n="7"' in snippet("x", 7)
    assert 'onerror="' in snippet('"', 1) and snippet('"', 1).count('"') % 2 == 0
