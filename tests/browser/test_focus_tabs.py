"""A scenario's focus step opens the focused device's tab of the left panel (docs/dashboard.md
"Focus"), so a checkpoint picture shows that device's state next to its caption.

A sales walkthrough of ``scenario run --screenshots`` found the FastCAT's State tab ("Fault
active FALSE", "Alarm none") in every picture, next to captions about the TRS-CAT, the
CPX-E-EC or the master. static/scenarios/cable_pulled.toml focuses the master (Line tab),
then the CPX-E-EC (Slave tab), then the master again.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import Any

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario

pytestmark = pytest.mark.browser

SCENARIO = DEFAULT_RIG.parent.parent / "scenarios" / "cable_pulled.toml"
# The left panel's tab bar is the one with the State tab (the control panel's has Scenario).
LEFT_TAB_JS = """() => { for (const list of document.querySelectorAll('[role=tablist]')) {
    const tabs = [...list.querySelectorAll('[role=tab]')];
    if (!tabs.some(t => t.textContent.trim() === 'State')) continue;
    const on = tabs.find(t => t.getAttribute('aria-selected') === 'true');
    return on ? on.textContent.trim() : ''; } return null; }"""


def left_tabs_at_checkpoints() -> list[tuple[str, str, str]]:
    """(checkpoint, selected left tab, Slave tab's device) as the screenshot run has the page
    at each checkpoint."""
    from app.screenshots import Chromium, play, served_run

    seen: list[tuple[str, str, str]] = []
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    with served_run(rig, quiet=True) as (served, _events), Chromium() as browser:
        page = browser.open(served, show_player=True)
        line = served.dashboard.line
        assert line is not None

        def look(step: Any) -> None:
            page.sync()
            seen.append((step.text, page.page.evaluate(LEFT_TAB_JS), line.slave.selected))

        assert play(served, load_scenario(SCENARIO), rig, look) == []
        page.close()
    return seen


def test_focus_steps_open_the_focused_devices_tab() -> None:
    with ThreadPoolExecutor(1) as pool:  # a Playwright of its own (test_screenshots_cli.py)
        seen = pool.submit(left_tabs_at_checkpoints).result(timeout=300)
    assert [(name, tab) for name, tab, _ in seen] == [
        ("line_in_op", "Line"), ("cable_pulled", "Slave"), ("recovered", "Line")]
    assert seen[1][2] == "cpx"
