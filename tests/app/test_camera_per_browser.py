"""A click in the 3D view moves the camera of the browser that clicked, not every browser's
(docs/dashboard.md "Several browsers"): several operators on one rig each look where they
want. Before, a click on a device (and "Show the whole line") sent every page a new camera.
Two websocket connections stand in for the browsers (tests/app/test_classroom_leak.py)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import msgspec
import pytest

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


def _moves_after(served: ServedRig, first: Page, second: Page, act: Any) -> tuple[int, int]:
    _settle(first, second)
    before = cameras(first), cameras(second)
    act()
    time.sleep(CLICK_SETTLE_S + 0.7)
    served.dashboard.tick()
    served.server.flush()
    time.sleep(0.3)
    return cameras(first) - before[0], cameras(second) - before[1]


def test_a_click_on_a_device_moves_only_the_clicking_browser_s_camera(
        served: tuple[ServedRig, Page, Page]) -> None:
    rig, first, second = served
    line = rig.dashboard.line
    assert line is not None
    node = line.scene.bodies["trscat"].clickables[0].name
    moved = _moves_after(rig, first, second, lambda: click(first, node))
    assert line.focused == "trscat"  # the click did arrive
    assert moved[0] >= 1 and moved[1] == 0, moved


def test_show_the_whole_line_moves_only_that_browser_s_camera(
        served: tuple[ServedRig, Page, Page]) -> None:
    rig, first, second = served
    button = second.widget("Show the whole line")
    moved = _moves_after(rig, first, second, lambda: second.set(button, True))
    assert moved[1] >= 1 and moved[0] == 0, moved


def test_a_scenario_focus_still_moves_every_browser(
        served: tuple[ServedRig, Page, Page]) -> None:
    """A demo follows the narration: a focus step is no browser's click."""
    rig, first, second = served
    line = rig.dashboard.line
    assert line is not None
    moved = _moves_after(rig, first, second, lambda: line.focus(None, "cpx"))
    assert moved[0] >= 1 and moved[1] >= 1, moved
