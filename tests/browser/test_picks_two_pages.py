"""Two browsers on one rig: what one picks in the Slave tab and the Servo drive picker stays
on its page; the other page keeps reading its own slave and drive (docs/dashboard.md "Several
browsers"). Before, the second page's Slave and Drive tabs switched with the first's pick."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from helpers import VIEWPORT, LiveDashboard, choose, open_dashboard, wait_until

BOOT_S = 4.0


def _open(page: Any, name: str) -> None:
    tabs = page.get_by_role("tab", name=name, exact=True)
    wait_until(lambda: tabs.count() >= 1, what=f"the tab {name!r}")
    for tab in tabs.all():
        tab.click()


@contextmanager
def _two_pages(live: LiveDashboard, browser: Any, *tabs: str) -> Iterator[list[Any]]:
    """Two browsers on the booted rig, each with ``tabs`` opened in turn."""
    live.advance(BOOT_S)
    pages = [browser.new_context(viewport=VIEWPORT, device_scale_factor=1).new_page()
             for _ in range(2)]
    try:
        for page in pages:
            open_dashboard(page, live)
            for tab in tabs:
                _open(page, tab)
        yield pages
    finally:
        for page in pages:
            page.context.close()


def _title(page: Any, css: str) -> str:
    return str(page.locator(css).first.inner_text())


def test_a_pick_on_one_page_leaves_the_other_page_s_tabs(live: LiveDashboard,
                                                         browser: Any) -> None:
    with _two_pages(live, browser, "Slave") as pages:
        for page in pages:
            page.locator("#fr-slave-state").wait_for()
        first, second = pages
        slave_title = ".fr-title:has-text('trscat'), .fr-title:has-text('cpx')"
        wait_until(lambda: "trscat" in _title(second, slave_title), what="trscat on page 2")
        choose(first, "Slave", "cpx")
        wait_until(lambda: "cpx" in _title(first, slave_title), what="cpx on page 1")
        _open(first, "Servo drive")
        _open(second, "Servo drive")
        for page in pages:
            _open(page, "Drive")
        choose(first, "Servo drive", "drive_co")
        drive_title = ".fr-title:has-text('node')"
        wait_until(lambda: "drive_co" in _title(first, drive_title), what="drive_co, page 1")
        live.advance(0.2)  # frames for both pages
        wait_until(lambda: "t = " in _title(second, drive_title), what="page 2's drive tab")
        assert _title(second, drive_title).startswith("drive ·")
        assert second.get_by_label("Servo drive", exact=True).input_value() == "drive"
        _open(second, "Slave")
        assert "trscat" in _title(second, slave_title)
        assert second.get_by_label("Slave", exact=True).input_value() == "trscat"


def _result(page: Any) -> str:
    """The line under the drive's register and parameter boxes ("" before any answer)."""
    found = page.locator("#fr-drive-result")
    return str(found.first.inner_text()) if found.count() else ""


def test_a_register_read_on_one_page_stays_on_that_page(live: LiveDashboard,
                                                        browser: Any) -> None:
    """The drive's Register box and the answer line under it are each page's own: page A's
    pick and read leave page B's box and line; B's read shows on B only."""
    with _two_pages(live, browser, "Servo drive") as pages:
        for page in pages:
            page.get_by_text("Registers and parameters").click()
        first, second = pages
        initial = second.get_by_label("Register", exact=True).input_value()
        choose(first, "Register", "R02 feed_constant")
        first.get_by_role("button", name="Read register").click()
        wait_until(lambda: "R02 feed_constant = " in _result(first), what="page 1's answer")
        live.advance(0.2)  # frames for both pages
        assert second.get_by_label("Register", exact=True).input_value() == initial
        assert _result(second) == ""
        choose(second, "Register", "R05 status_word")
        second.get_by_role("button", name="Read register").click()
        wait_until(lambda: "R05 status_word = " in _result(second), what="page 2's answer")
        live.advance(0.2)
        assert "R02 feed_constant = " in _result(first)
        assert first.get_by_label("Register", exact=True).input_value() == "R02 feed_constant"


def _picked(page: Any, label: str) -> str:
    return str(page.get_by_label(label, exact=True).first.input_value())


def test_a_module_pick_and_its_unplug_stay_on_their_page(live: LiveDashboard,
                                                         browser: Any) -> None:
    """The FastCAT tab's Module: page 1 picks module 3, page 2 keeps module 1 and its Unplug
    pulls module 1 (seed 000 §2). Before, page 2's picker showed module 3 and its Unplug
    pulled the module page 1 had picked."""
    with _two_pages(live, browser) as pages:
        first, second = pages
        wait_until(lambda: _picked(second, "Module") == "1 DB16", what="module 1 on page 2")
        choose(first, "Module", "3 DO16")
        wait_until(lambda: _picked(first, "Module") == "3 DO16", what="module 3 on page 1")
        live.advance(0.2)  # frames for both pages
        assert _picked(second, "Module") == "1 DB16"
        second.get_by_role("button", name="Unplug").click()
        live.wait_for_state(lambda s: s["rail"][0]["type"] is None, "module 1 off the rail")
        assert live.snapshot()["rail"][2]["type"] == "DO16"
        live.advance(0.2)
        wait_until(lambda: _picked(second, "Module") == "1 (empty)", what="its new label")
        # Page 1 got the new default "1 (empty)" too (where new pages start), then its own
        # pick back once that broadcast reached it (ClientPick.resend): not at the same time.
        wait_until(lambda: _picked(first, "Module") == "3 DO16", what="page 1's own pick")


def _shown(page: Any, label: str) -> int:
    """How many boxes labelled ``label`` the page shows (a hidden folder's are not)."""
    boxes = page.get_by_label(label, exact=True)
    return sum(1 for box in boxes.all() if box.is_visible())


def test_a_drive_action_picked_on_one_page_shows_its_parameters_there_only(
        live: LiveDashboard, browser: Any) -> None:
    """The Drive action form is each page's own: every action's parameters are built once,
    each in a folder hidden but on the pages that picked it. Page A's write_register shows
    A its register and value boxes; page B keeps its own pick and no such box."""
    with _two_pages(live, browser, "Servo drive") as pages:
        for page in pages:
            page.get_by_text("Other drive actions").click()
        first, second = pages
        initial = second.get_by_label("Drive action", exact=True).input_value()
        assert initial != "write_register" and _shown(second, "register") == 0
        choose(first, "Drive action", "write_register")
        wait_until(lambda: _shown(first, "register") == 1 and _shown(first, "value") == 1,
                   what="page 1's write_register boxes")
        live.advance(0.2)  # frames for both pages
        assert second.get_by_label("Drive action", exact=True).input_value() == initial
        assert _shown(second, "register") == 0 and _shown(second, "value") == 0
        choose(second, "Drive action", "read_register")
        wait_until(lambda: _shown(second, "register") == 1, what="page 2's read_register box")
        assert _shown(second, "value") == 0
        assert first.get_by_label("Drive action", exact=True).input_value() == "write_register"
        assert _shown(first, "register") == 1 and _shown(first, "value") == 1
