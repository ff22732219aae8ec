"""A focus sends the browser its camera whatever the page reported before.

viser 1.1.1's camera setters (``CameraHandle.position`` / ``look_at``) return without sending
when the new value is ``np.allclose`` to the handle's state, and that state is the pose the
page REPORTED last (its throttled camera messages), or the last one set on the server. Whether
a focus reached the browser then depended on what the page had said before: a page that had
been at the focus pose and moved since (an orbit whose report was not in yet) kept its view.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import viser
from served_dashboard import ticked_dashboard
from viser._messages import (  # viser 1.1.1, pinned
    SetCameraLookAtMessage,
    SetCameraPositionMessage,
    SetCameraUpDirectionMessage,
)

from app.ui.dashboard import Dashboard

CANVAS = (552, 672)  # the 3D view of the 1280 x 720 screenshot page, as its camera reports it


@pytest.fixture(scope="module")
def dashboard() -> Iterator[Dashboard]:
    with ticked_dashboard() as dashboard:
        yield dashboard


class Page:
    """A browser as viser's server sees it: a real CameraHandle, the messages queued for it."""

    def __init__(self, client_id: int = 1) -> None:
        self.client_id = client_id
        self.sent: list[Any] = []
        self._websock_connection = SimpleNamespace(queue_message=self.sent.append)
        self.camera = viser.CameraHandle(self)  # type: ignore[arg-type]

    def atomic(self) -> contextlib.AbstractContextManager[None]:
        return contextlib.nullcontext()

    def reports(self, position: Any, look_at: Any) -> None:
        """The page's camera message, as viser's handler stores it (viser/_viser.py)."""
        width, height = CANVAS
        self.camera._state = dataclasses.replace(
            self.camera._state, position=np.array(position, dtype=float),
            look_at=np.array(look_at, dtype=float), up_direction=np.array([0.0, 0.0, 1.0]),
            image_width=width, image_height=height, update_timestamp=time.time())

    def last(self, kind: type) -> tuple[float, ...]:
        found = [m for m in self.sent if isinstance(m, kind)]
        assert found, f"no {kind.__name__} sent: {self.sent}"
        message = found[-1]
        return tuple(message.look_at if kind is SetCameraLookAtMessage else message.position)


def scenario_focus(dashboard: Dashboard, page: Page, device: str,
                   monkeypatch: pytest.MonkeyPatch) -> tuple[Any, Any]:
    """A scenario's focus step on ``device`` with ``page`` the one browser; the pose due."""
    line = dashboard._line
    assert line is not None
    monkeypatch.setattr(line._server, "get_clients", lambda: {page.client_id: page})
    line.add_events([SimpleNamespace(kind="focus", target=device)])  # type: ignore[list-item]
    return line.focus_camera(device, CANVAS[0] / CANVAS[1])


def test_a_focus_is_sent_when_the_page_reported_a_pose_close_to_it(
        dashboard: Dashboard, monkeypatch: pytest.MonkeyPatch) -> None:
    line = dashboard._line
    assert line is not None
    position, look_at = line.focus_camera("cpx", CANVAS[0] / CANVAS[1])
    page = Page()
    # within np.allclose of the focus pose: viser's setters took it for "already there"
    page.reports(np.array(position) * (1 + 1e-7), np.array(look_at) * (1 + 1e-7))
    scenario_focus(dashboard, page, "cpx", monkeypatch)
    assert page.last(SetCameraPositionMessage) == pytest.approx(position)
    assert page.last(SetCameraLookAtMessage) == pytest.approx(look_at)
    assert page.last(SetCameraUpDirectionMessage) == pytest.approx((0.0, 0.0, 1.0))


def test_a_focus_sends_the_same_messages_whatever_the_page_reported(
        dashboard: Dashboard, monkeypatch: pytest.MonkeyPatch) -> None:
    """The page at the whole line, at the focus pose itself, or not reported since the
    server's last move: the browser is told the same pose in the same messages each time."""
    line = dashboard._line
    assert line is not None
    position, look_at = line.focus_camera("cpx", CANVAS[0] / CANVAS[1])
    sent = []
    for reported in ((3.4, -24.2, -2.7, 3.4, 0.0, -5.6), (*position, *look_at), None):
        page = Page()
        if reported is not None:
            page.reports(reported[:3], reported[3:])
        else:  # the server moved it there last; the page has said nothing since
            page.reports((0.0, -20.0, 0.0), (0.0, 0.0, 0.0))
            scenario_focus(dashboard, page, "cpx", monkeypatch)
            page.sent.clear()
        scenario_focus(dashboard, page, "cpx", monkeypatch)
        sent.append([(type(m).__name__, m) for m in page.sent])
    assert sent[0] == sent[1] == sent[2]
    assert page.last(SetCameraPositionMessage) == pytest.approx(position)
    assert page.last(SetCameraLookAtMessage) == pytest.approx(look_at)
