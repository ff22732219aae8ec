"""What a page types in a form and the answer it reads are that page's own (docs/dashboard.md
"Several browsers", docs/classroom.md): the drive's Target position, Register and Parameter
boxes and the line under them, the Objects tab's Filter, Object and Value boxes, the Codes
tab's Code box, Reported pick and result. Before, a trainee typing a register number changed
every classmate's box, and one page's read result appeared on every page. Two websocket
connections stand in for the browsers (tests/app/test_picks_per_browser.py)."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from app.ui.drive.drive_options import register_option
from app.ui.panels.classroom_rig import ServedRig
from devices.events import AlStatusChanged
from devices.servo.registers import R
from tests.app.test_classroom_leak import Page, _wait
from tests.app.test_picks_per_browser import _widget, contents
from tests.app.two_pages import one_drive_pages, two_pages


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages() as pages:
        yield pages


@pytest.fixture(scope="module")
def one_drive(tmp_path_factory: pytest.TempPathFactory
              ) -> Iterator[tuple[ServedRig, Page, Page]]:
    """One drive, one dictionary: no picker makes a page's Register box its own there."""
    with one_drive_pages(tmp_path_factory.mktemp("rig")) as pages:
        yield pages


def _frames(live: ServedRig, n: int = 3) -> None:
    """A few dashboard frames (the test's own: the served one runs too), then the wire."""
    for _ in range(n):
        live.dashboard.tick()
        time.sleep(0.1)
    live.server.flush()
    time.sleep(0.3)


def _has(page: Page, text: str) -> bool:
    return any(text in c for c in contents(page))


def _drive_read(page: Page, register: str) -> None:
    page.set(_widget(page, "Register", register), register)
    time.sleep(0.1)  # the page's sender: one message each 50 ms window
    page.set(_widget(page, "Register access", "Read register"), "Read register")


@pytest.mark.parametrize("rig", ["served", "one_drive"])
def test_a_register_read_on_one_page_shows_on_that_page_only(
        rig: str, request: pytest.FixtureRequest) -> None:
    live, first, second = request.getfixturevalue(rig)
    box = _widget(first, "Register", "R02 feed_constant")
    _drive_read(first, "R02 feed_constant")
    _wait(lambda: _has(first, "R02 feed_constant = "))
    _frames(live)
    assert "R02 feed_constant" not in second.updates(box)  # B's box was not changed
    assert not _has(second, "fr-drive-result")  # nor its result line
    # B has picked no register: its Read reads the one its box shows, not the one A picked
    initial = register_option(R.PROFILE_VELOCITY)
    second.set(_widget(second, "Register access", "Read register"), "Read register")
    _wait(lambda: _has(second, f"{initial} = "))
    _frames(live)
    assert not _has(second, "R02 feed_constant = ") and not _has(first, f"{initial} = ")
    _drive_read(second, "R05 status_word")
    _wait(lambda: _has(second, "R05 status_word = "))
    _frames(live)
    assert not _has(first, "R05 status_word = ")
    assert not _has(second, "R02 feed_constant = ")


def test_the_register_hint_follows_the_page_s_own_register(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    box = _widget(first, "Register", "R09 target_position")
    first.set(box, "R09 target_position")
    _wait(lambda: any("R09 target_position: " in str(h) for h in _hints(first, box)))
    _frames(live)
    assert not any("R09 target_position: " in str(h) for h in _hints(second, box))


def _hints(page: Page, uuid: str) -> list[object]:
    return [m["updates"]["hint"] for m in page.received()
            if m.get("type") == "GuiUpdateMessage" and m.get("uuid") == uuid
            and "hint" in (m.get("updates") or {})]


def _objects_on_cpx(live: ServedRig) -> None:
    """Every page's Objects tab on the CPX-E-EC: its dictionary is there without a scan (the
    rig is paused; the FastCAT builds its own after the first scan)."""
    objects = live.dashboard.objects
    assert objects is not None
    objects.select("cpx")


def object_read(live: ServedRig, page: Page, address: str) -> str:
    """``page`` types ``address`` in the Objects tab's Object box and reads it: the Value box's
    uuid, once the page got a value and a few frames went out after it."""
    value = _widget(page, "Value", None)
    page.set(_widget(page, "Object", None), address)
    time.sleep(0.1)  # the page's sender: one message each 50 ms window
    page.set(_widget(page, "Access", "Read"), "Read")
    _wait(lambda: page.updates(value))
    _frames(live)
    return value


def test_an_object_read_fills_the_reading_page_s_value_box_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    _objects_on_cpx(live)
    value = object_read(live, first, "0x1018:1")
    address = _widget(first, "Object", None)
    assert second.updates(value) == [] and "0x1018:1" not in second.updates(address)
    object_read(live, second, "0x1000:0")  # B's Read reads the object B typed, into B's box
    assert second.updates(value) == ["0x04561389"]  # 72749961, the CPX-E-EC's 0x1000
    assert first.updates(value) == ["0x0000001D"]  # the vendor id A read (29)


def test_a_filter_typed_on_one_page_filters_that_page_s_table_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    _objects_on_cpx(live)
    first.set(_widget(first, "Filter", None), "1018")
    _wait(lambda: any("fr-od" in c and "0x1018:1" in c and "0x1000:0" not in c
                      for c in contents(first)))
    _frames(live)
    tables = [c for c in contents(second) if "fr-od" in c]
    assert tables and "0x1000:0" in tables[-1]  # B's table: unfiltered


def _decoded(page: Page, code: str) -> bool:
    """The page got the Codes tab's answer for ``code`` (its head line is the query)."""
    return any("fr-decoded" in c and f'fr-muted">{code}' in c for c in contents(page))


def test_a_code_decoded_on_one_page_shows_on_that_page_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    code = _widget(first, "Code", None)
    first.set(code, "0x001B")
    _wait(lambda: _decoded(first, "0x001B"))
    _frames(live)
    assert not _decoded(second, "0x001B") and "0x001B" not in second.updates(code)
    second.set(code, "0x0011")
    _wait(lambda: _decoded(second, "0x0011"))
    _frames(live)
    assert not _decoded(first, "0x0011")


def _report(live: ServedRig, t_s: int, code: int) -> str:
    """The rig reports an AL status code; its label in the Reported list."""
    live.runtime.journal([AlStatusChanged(t_s * 1_000_000, "trscat", code=code)])
    return f"{t_s}.0 s trscat AL status code 0x{code:04X}"


def test_a_reported_code_picked_on_one_page_is_picked_there_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    """Two new pages follow the newest code until they pick or type; a page's pick decodes
    on that page; a page holding its own query keeps it when a new code comes, the other
    page follows the newest."""
    live = served[0]
    first, second = Page(live.port), Page(live.port)
    try:
        _wait(lambda: len(live.server.get_clients()) == 4)
        _reported_on_two_pages(live, first, second)
    finally:
        first.close()
        second.close()


def _reported_on_two_pages(live: ServedRig, first: Page, second: Page) -> None:
    older, newer = _report(live, 1, 0x001D), _report(live, 2, 0x0016)
    picker, code = _widget(first, "Reported", None), _widget(first, "Code", None)
    _wait(lambda: _decoded(first, newer) and _decoded(second, newer))
    first.set(picker, older)
    _wait(lambda: _decoded(first, older) and "0x001D" in first.updates(code))
    _frames(live)
    assert older not in second.updates(picker) and not _decoded(second, older)
    assert second.updates(code)[-1] == "0x0016"
    time.sleep(0.1)
    first.set(code, "0x001A")  # A's own query
    _wait(lambda: _decoded(first, "0x001A"))
    newest = _report(live, 3, 0x0014)
    _wait(lambda: _decoded(second, newest))
    _frames(live)
    assert not _decoded(first, newest) and newest not in first.updates(picker)
    assert first.updates(code)[-1] == "0x001D"  # the box holds what A typed since


def test_a_page_that_left_leaves_no_codes_tab_view_behind(
        served: tuple[ServedRig, Page, Page]) -> None:
    """Each page's Code box, pick and answer are kept while it is there: a classroom's pages
    come and go for hours, and every one that typed a code stayed in memory for good."""
    live = served[0]
    before = set(live.server.get_clients())
    page = Page(live.port)
    try:
        # its id is new (viser counts up); a page of an earlier test may still be leaving
        (mine,) = _wait(lambda: set(live.server.get_clients()) - before)
        page.set(_widget(page, "Code", None), "0x0011")
        _wait(lambda: _decoded(page, "0x0011"))
        assert mine in live.dashboard.decoder._views
    finally:
        page.close()
    _wait(lambda: mine not in live.server.get_clients())
    _frames(live)
    assert mine not in live.dashboard.decoder._views
