"""A click in the 3D view moves the camera of the browser that clicked, not every browser's
(docs/dashboard.md "Several browsers"): several operators on one rig each look where they
want. Before, a click on a device (and "Show the whole line") sent every page a new camera.
Two websocket connections stand in for the browsers (tests/app/test_classroom_leak.py)."""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import msgspec
import pytest
from viser._messages import RunJavascriptMessage  # viser 1.1.1, pinned

from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.line.view import CLICK_SETTLE_S
from app.ui.panels.classroom_rig import ServedRig, serve_rig
from tests.app.test_classroom_leak import Page, _wait


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(None), port=free_port(), paused=True)  # an open rig
    first, second = Page(served.port), Page(served.port)
    try:
        _wait(lambda: len(served.server.get_clients()) == 2)
        _settle(first, second)  # both pages built, their first camera sent
        yield served, first, second
    finally:
        first.close()
        second.close()
        served.stop()


def cameras(page: Page) -> int:
    """How many camera moves the server sent this page."""
    return sum(1 for m in page.received() if m.get("type") == "SetCameraPositionMessage")


def click(page: Page, node: str) -> None:
    """What the browser sends when its user clicks a shared scene node."""
    page._ws.send(msgspec.msgpack.encode({
        "type": "SceneNodeClickMessage", "name": node, "instance_index": None,
        "ray_origin": (0.0, -5.0, 0.0), "ray_direction": (0.0, 1.0, 0.0),
        "screen_pos": (0.5, 0.5), "modifier": None, "owner": ""}))


def _settle(first: Page, second: Page, quiet_s: float = 1.5, timeout_s: float = 30.0) -> None:
    """Until neither page got a camera move for ``quiet_s``: a page's connection-time camera
    can arrive late on a loaded machine (a CI run once counted one in a click's window)."""
    deadline = time.monotonic() + timeout_s
    last, since = (cameras(first), cameras(second)), time.monotonic()
    while time.monotonic() - since < quiet_s:
        assert time.monotonic() < deadline, "the pages' cameras never settled"
        time.sleep(0.1)
        now = cameras(first), cameras(second)
        if now != last:
            last, since = now, time.monotonic()


_probes = itertools.count()
QUIET_S = 0.5  # how long a page that must not move is watched, once the server is through


def _probe(served: ServedRig, *pages: Page) -> None:
    """Until each page got a message the server queued for it now: what the server had
    queued for a page before (a camera move of the same action) has reached it (a
    connection's messages go out in the order they were queued)."""
    source = f"// probe {next(_probes)}"
    for client in served.server.get_clients().values():
        client._websock_connection.queue_message(RunJavascriptMessage(source=source))
    _wait(lambda: all(any(m.get("source") == source for m in page.received())
                      for page in pages))


def _moves_after(served: ServedRig, first: Page, second: Page, act: Any,
                 expect: tuple[bool, bool]) -> tuple[int, int]:
    """The camera moves each page got from ``act``. A page ``expect``ed to move is waited
    for (a click's move comes CLICK_SETTLE_S after it); a page that must not move is watched
    only after a positive sign that the server is through with the action: the other page's
    move arrived, then a probe queued after it reached this page, and QUIET_S more."""
    _settle(first, second)
    pages = first, second
    before = cameras(first), cameras(second)

    def moved() -> tuple[int, int]:
        return cameras(first) - before[0], cameras(second) - before[1]

    act()
    _wait(lambda: all(n >= 1 for n, want in zip(moved(), expect, strict=True) if want))
    if not all(expect):
        _probe(served, *pages)
        time.sleep(QUIET_S)
    return moved()


def test_a_click_on_a_device_moves_only_the_clicking_browser_s_camera(
        served: tuple[ServedRig, Page, Page]) -> None:
    rig, first, second = served
    line = rig.dashboard.line
    assert line is not None
    node = line.scene.bodies["trscat"].clickables[0].name
    moved = _moves_after(rig, first, second, lambda: click(first, node), (True, False))
    assert line.focused == "trscat"  # the click did arrive
    assert moved[0] >= 1 and moved[1] == 0, moved


def test_show_the_whole_line_moves_only_that_browser_s_camera(
        served: tuple[ServedRig, Page, Page]) -> None:
    rig, first, second = served
    button = second.widget("Show the whole line")
    moved = _moves_after(rig, first, second, lambda: second.set(button, True), (False, True))
    assert moved[1] >= 1 and moved[0] == 0, moved


def test_a_scenario_focus_still_moves_every_browser(
        served: tuple[ServedRig, Page, Page]) -> None:
    """A demo follows the narration: a focus step is no browser's click."""
    rig, first, second = served
    line = rig.dashboard.line
    assert line is not None
    moved = _moves_after(rig, first, second, lambda: line.focus(None, "cpx"), (True, True))
    assert moved[0] >= 1 and moved[1] >= 1, moved


# viser's client draws its built-in default camera until it applies the server's initial
# camera, and its first camera report (the one that makes it a client: on_client_connect)
# can come before that: the server's initial-camera messages only fill a store, which a
# React effect applies later (viser/client/src/CameraControls.tsx, InitialCameraSetter;
# seen 2-7 s after the first report in Chromium here). Applying it overwrites any move the
# server sent the page before, and the page reports the new pose.
VIEWER_DEFAULT = ((3.0, 3.0, 3.0), (0.0, 0.0, 0.0))


class JoiningPage(Page):
    """A browser that connects: first reports ``first`` (viser's default pose unless told),
    then, at :meth:`apply_initial_camera`, the server's initial camera."""

    def __init__(self, port: int, first: tuple[Any, Any] = VIEWER_DEFAULT) -> None:
        super().__init__(port, *first)
        self._applied_at = 0  # messages received before the page last applied its initial

    def initial_camera(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The initial camera the server sent (messages marked ``initial``)."""
        return self._pose(self.received(), initial=True)

    def apply_initial_camera(self) -> None:
        messages = self.received()
        self._applied_at = len(messages)
        self.report_camera(*self._pose(messages, initial=True))

    def shows(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The pose the page is at: the server's moves after it applied its initial camera
        (those before were overwritten), else the initial camera."""
        position, look_at = self.initial_camera()
        later = self._pose(self.received()[self._applied_at:], initial=False)
        return later[0] or position, later[1] or look_at

    @staticmethod
    def _pose(messages: list[dict[str, Any]], initial: bool,
              ) -> tuple[tuple[float, ...], tuple[float, ...]]:
        position: tuple[float, ...] = ()
        look_at: tuple[float, ...] = ()
        for m in messages:
            if m.get("initial", False) != initial:
                continue
            if m.get("type") == "SetCameraPositionMessage":
                position = tuple(m["position"])
            elif m.get("type") == "SetCameraLookAtMessage":
                look_at = tuple(m["look_at"])
        return position, look_at


def _moves(page: Page) -> int:
    """The camera moves (not the initial camera) the server sent ``page``."""
    return sum(1 for m in page.received()
               if m.get("type") == "SetCameraPositionMessage" and not m.get("initial"))


def _quiet(served: ServedRig) -> None:
    """Until the server has answered what a page sent (its camera report)."""
    time.sleep(CLICK_SETTLE_S + 0.7)
    served.server.flush()
    time.sleep(0.3)


@contextmanager
def _joining(served: ServedRig, first: tuple[Any, Any] = VIEWER_DEFAULT,
             ) -> Iterator[JoiningPage]:
    page = JoiningPage(served.port, first)
    try:
        _wait(lambda: len(served.server.get_clients()) == 3)
        _wait(lambda: page.initial_camera()[0] and page.initial_camera()[1])
        _quiet(served)
        yield page
    finally:
        page.close()
        _wait(lambda: len(served.server.get_clients()) == 2)


PAGE_ASPECT = 1280 / 720  # the canvas a JoiningPage reports


def _flat(pose: tuple[Any, Any]) -> tuple[float, ...]:
    """(position, look_at) as six numbers, for pytest.approx."""
    return (*pose[0], *pose[1])


def test_a_page_that_joins_during_a_scenario_focus_shows_the_focused_camera(
        served: tuple[ServedRig, Page, Page]) -> None:
    """A scenario's focus hides the labels its view would cut and grows the master's screen
    texts for every browser; a page opened (or reloaded) during it showed the whole line
    under that label state: labels missing over most of the line, "DC COMPENSATING" wider
    than the master's screen (baseline line_trscat_outputs). A move sent when the page
    connects is overwritten by the page's own initial camera: it must follow that."""
    rig, _first, _second = served
    line = rig.dashboard.line
    assert line is not None
    line.focus(None, "trscat")
    focused = line.focus_camera("trscat", PAGE_ASPECT)
    with _joining(rig) as page:
        page.apply_initial_camera()
        _quiet(rig)
        assert _flat(page.shows()) == pytest.approx(_flat(focused), abs=1e-6), page.shows()
        # Once there, the page is its user's: a later return to the initial camera (viser's
        # "Reset view") is not undone.
        page.report_camera(*focused)
        moves = _moves(page)
        page.apply_initial_camera()
        _quiet(rig)
        assert _moves(page) == moves
    line.show_all(None)


def test_a_page_whose_first_report_is_its_initial_camera_gets_the_focus(
        served: tuple[ServedRig, Page, Page]) -> None:
    """A page that applied the initial camera before its first report (a fast one)."""
    rig, _first, _second = served
    line = rig.dashboard.line
    assert line is not None
    line.focus(None, "trscat")
    focused = line.focus_camera("trscat", PAGE_ASPECT)
    initial = rig.server.initial_camera
    first = (tuple(initial.position), tuple(initial.look_at))
    with _joining(rig, first) as page:
        assert _flat(page.shows()) == pytest.approx(_flat(focused), abs=1e-6), page.shows()
    line.show_all(None)


def test_a_focus_that_starts_while_a_page_joins_reaches_it(
        served: tuple[ServedRig, Page, Page]) -> None:
    """The scenario's focus moves every page, the joining one too, before that page applied
    its initial camera, which then overwrites the move."""
    rig, _first, _second = served
    line = rig.dashboard.line
    assert line is not None
    line.show_all(None)
    with _joining(rig) as page:
        line.focus(None, "trscat")
        _quiet(rig)
        page.apply_initial_camera()
        _quiet(rig)
        focused = line.focus_camera("trscat", PAGE_ASPECT)
        assert _flat(page.shows()) == pytest.approx(_flat(focused), abs=1e-6), page.shows()
    line.show_all(None)


def test_a_page_that_joins_with_no_focus_keeps_its_initial_camera(
        served: tuple[ServedRig, Page, Page]) -> None:
    rig, _first, _second = served
    line = rig.dashboard.line
    assert line is not None
    line.show_all(None)  # no focus shared (an earlier test's scenario focus ends)
    with _joining(rig) as page:
        page.apply_initial_camera()
        _quiet(rig)
        assert _moves(page) == 0
        assert page.shows() == page.initial_camera()
