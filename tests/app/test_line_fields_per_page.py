"""The Line tab's Spoiled % and Frames to lose boxes and its *ESC counters of* picker are each
page's own on an open rig (docs/dashboard.md "Several browsers"): what page A types or picks
there moves nothing on page B, and B's Damage, Lose frames and Clear ESC error counters send
B's own values. Before, they were one widget for every page: A's 50 % showed in B's box and
B's Damage spoiled half the frames. Two websocket connections stand in for the browsers."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from form_page import uuid
from viser_page import Page, wait

from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_forms_per_browser import _frames
from tests.app.two_pages import two_pages

Sent = list[tuple[str, str, dict[str, Any]]]


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages() as pages:
        yield pages


@pytest.fixture
def sent(served: tuple[ServedRig, Page, Page]) -> Iterator[Sent]:
    """What the dashboard commands from now on (still applied)."""
    runtime = served[0].runtime
    command = runtime.command
    got: Sent = []

    def recorded(target: str, action: str, args: Any = None) -> Any:
        got.append((target, action, dict(args or {})))
        return command(target, action, args)

    runtime.command = recorded  # type: ignore[method-assign]
    try:
        yield got
    finally:
        del runtime.command


def _master(sent: Sent, action: str) -> list[dict[str, Any]]:
    return [args for _target, name, args in sent if name == action]


def test_spoiled_percent_is_each_page_s_own(served: tuple[ServedRig, Page, Page],
                                            sent: Sent) -> None:
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    spoiled = uuid(controls.damage)
    first.set(spoiled, 50)
    _frames(live)
    assert 50 not in second.updates(spoiled)
    damage = uuid(controls._cables.each()[0].damage_ops)
    second.set(damage, "Damage")
    wait(lambda: _master(sent, "damage_cable"))
    assert _master(sent, "damage_cable")[0]["percent"] == 10  # B's box: the initial 10 %
    first.set(damage, "Damage")
    wait(lambda: len(_master(sent, "damage_cable")) == 2)
    assert _master(sent, "damage_cable")[1]["percent"] == 50
    first.set(damage, "Repair")
    wait(lambda: _master(sent, "repair_cable"))


def test_frames_to_lose_is_each_page_s_own(served: tuple[ServedRig, Page, Page],
                                           sent: Sent) -> None:
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    frames = uuid(controls.frames)
    first.set(frames, 500)
    _frames(live)
    assert 500 not in second.updates(frames)
    lose = uuid(controls._frames.each()[0].lose)
    second.set(lose, True)
    wait(lambda: _master(sent, "lose_frames"))
    assert _master(sent, "lose_frames") == [{"count": 10}]  # B's: the initial 10
    first.set(lose, True)
    wait(lambda: len(_master(sent, "lose_frames")) == 2)
    assert _master(sent, "lose_frames")[1] == {"count": 500}


def test_esc_counters_of_is_each_page_s_own(served: tuple[ServedRig, Page, Page],
                                            sent: Sent) -> None:
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    picker = uuid(controls.esc_slave)
    first.set(picker, "2 cpx")
    _frames(live)
    assert "2 cpx" not in second.updates(picker)
    clear = next(str(m["uuid"]) for m in second.received()
                 if (m.get("props") or {}).get("label") == "Clear ESC error counters")
    second.set(clear, True)
    wait(lambda: _master(sent, "clear_esc_errors"))
    assert _master(sent, "clear_esc_errors") == [{"position": 0}]  # B's: the first slave
    first.set(clear, True)
    wait(lambda: len(_master(sent, "clear_esc_errors")) == 2)
    assert _master(sent, "clear_esc_errors")[1] == {"position": 2}
