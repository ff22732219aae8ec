"""The Scenario tab's picker is each page's own on an open rig (docs/dashboard.md "Several
browsers"): the file a page will load, its hint and its "Picked:" line; Play, Step and Restart
load the clicking page's pick. The scenario that is loaded stays the rig's, as the player is:
a load names it in every page's picker. Before, the picker was one for every page: page A's
pick showed on page B, and B's Play loaded the scenario A had picked. Two websocket
connections stand in for the browsers."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from form_page import uuid
from viser_page import Page, wait

from app.ui.panels.classroom_rig import ServedRig
from app.ui.panels.scenario_player import CHOOSE, PLAY, library
from tests.app.test_action_forms_per_page import last_prop
from tests.app.test_forms_per_browser import _frames, _has
from tests.app.test_picks_per_browser import _widget
from tests.app.two_pages import two_pages


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages() as pages:
        yield pages


def test_the_scenario_pick_is_each_page_s_and_play_loads_it(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    panel = live.dashboard.scenario_player
    picker = uuid(panel._controls.each()[0].pick)
    entry = next(e for e in library() if e.path.name == "cpx_short_circuit.toml")
    first.set(picker, entry.label)
    wait(lambda: str(last_prop(first, picker, "hint")).startswith(entry.scenario.name))
    wait(lambda: _has(first, f"Picked: <b>{entry.scenario.name}</b>"))
    _frames(live)
    assert entry.label not in second.updates(picker)
    assert not str(last_prop(second, picker, "hint")).startswith(entry.scenario.name)
    assert not _has(second, f"Picked: <b>{entry.scenario.name}</b>")
    playback = _widget(second, "Playback", None)
    second.set(playback, PLAY)  # B picked nothing: refused, nothing loaded
    _frames(live)
    assert panel.player.view().scenario is None
    first.set(playback, PLAY)
    wait(lambda: (view := panel.player.view()).scenario is not None
         and view.scenario.name == entry.scenario.name)
    # the loaded scenario is the rig's: every page's picker names it
    wait(lambda: second.updates(picker) and second.updates(picker)[-1] == entry.label)
    assert CHOOSE not in first.updates(picker)
