"""The Scenario tab in a classroom (docs/classroom.md "What a trainee does not see"): the
player's controls are the instructor's, and a running exercise's scenario shows under a
neutral title. Before, every page got Play, Pause, Step, Restart, Speed and the picker; each
trainee's press was refused and cost 2 points, and the exercise file's title ("Coupler lost
its node 0x04") and description named the hidden fault in the shared status block and in the
event log's new-run row. Two websocket connections stand in for the browsers."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from test_classroom_leak import Page, _try, _wait, open_class, text

from app.classroom.roles import Access
from app.player import Status
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import EXAMPLES_DIR, load_scenario
from app.screenshots import free_port
from app.ui.panels.classroom_rig import ServedRig, serve_rig
from app.ui.panels.scenario_player import PLAYER_FOLDER, STATUS_ID

TITLE = "Coupler lost its node"
DESCRIPTION = "The coupler reports 0x04 MISSING_NODE_ANSWER after a while"
FILE = f"""\
[scenario]
name = "{TITLE}"
description = "{DESCRIPTION}."
duration_s = 1

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true

[[step]]
at = 0.5
caption = "The line runs: watch the coupler."

[exercise]
fault = "fastcat:inject:coupler:0x04"
at_s = 1.0
"""
PLAIN = "Module 2 stops answering in OP"
PLAIN_LABEL = "Module 2 lost in OP"  # the picker shows a scenario by its label
PLAIN_FILE = EXAMPLES_DIR / "module_lost_in_op.toml"


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[ServedRig, Page, Page, Path]]:
    path = tmp_path / "lost_node.toml"
    path.write_text(FILE)
    with open_class(exercise_files=[path]) as (one, trainee, instructor):
        _wait(lambda: "Hidden fault" in text(instructor))
        yield one, trainee, instructor, path


def _labels(page: Page) -> set[str]:
    return {str((m.get("props") or {}).get("label")) for m in page.received()}


def status(page: Page) -> str:
    """The newest content of the Scenario tab's status block this page got, as text."""
    for m in reversed(page.received()):
        content = (m.get("updates") or {}).get("content") or (m.get("props") or {}).get(
            "content")
        if isinstance(content, str) and f'id="{STATUS_ID}"' in content:
            return re.sub(r"<[^>]+>", "", content)
    raise KeyError(STATUS_ID)


def test_a_trainee_is_offered_no_player_control(
        served: tuple[ServedRig, Page, Page, Path]) -> None:
    one, trainee, instructor, _path = served
    controls = {"Playback", "Speed", "Scenario"}
    _wait(lambda: controls <= _labels(instructor))
    time.sleep(0.5)
    assert not controls & _labels(trainee), controls & _labels(trainee)
    assert PLAYER_FOLDER in text(trainee)  # the folder and its status block stay everyone's
    assert "No scenario loaded" in status(trainee)
    # The instructor's own copy plays: picked and Play pressed from its page, no refusal.
    instructor.set(instructor.last("Scenario", PLAIN_LABEL), PLAIN_LABEL)
    time.sleep(0.3)
    instructor.set(instructor.last("Playback", "Play"), "Play")
    player = one.dashboard.scenario_player.player
    _wait(lambda: player.view().status is Status.PLAYING)
    assert player.view().scenario.name == PLAIN  # type: ignore[union-attr]
    assert not one.classroom.refusals
    _wait(lambda: PLAIN in status(trainee))  # a plain scenario's title is no secret


def test_an_exercise_file_s_title_is_the_instructor_s(
        served: tuple[ServedRig, Page, Page, Path]) -> None:
    one, trainee, instructor, path = served
    one.classroom.start_from_file(path)
    one.runtime.advance(1_500_000).result(timeout=60)
    _wait(lambda: one.classroom.exercise is not None)
    _wait(lambda: "Exercise 1" in _try(status, trainee) or "")
    _wait(lambda: "watch the coupler" in status(trainee))  # the narration is everyone's
    _wait(lambda: f"loaded: <b>{TITLE}</b> (lost_node.toml)" in text(instructor))
    time.sleep(0.5)
    got = text(trainee)
    assert TITLE not in got and DESCRIPTION not in got
    assert "scenario &#x27;Exercise 1&#x27; started" in got  # the event log's new-run row
    one.classroom.finish(as_instructor=True)
    _wait(lambda: TITLE in status(trainee))  # scored: the answer is out


def test_an_exercise_from_the_folder_hides_the_loaded_title(
        served: tuple[ServedRig, Page, Page, Path]) -> None:
    one, trainee, _instructor, _path = served
    one.dashboard.scenario_player.load(load_scenario(PLAIN_FILE))
    _wait(lambda: PLAIN in _try(status, trainee) or "")
    one.classroom.start_exercise("fastcat:inject:coupler:0x04")
    _wait(lambda: "Exercise 1" in status(trainee))
    assert PLAIN not in status(trainee)
    one.classroom.finish(as_instructor=True)
    _wait(lambda: PLAIN in status(trainee))


def test_an_open_rig_keeps_the_shared_controls() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    one = serve_rig(rig, Access(None), port=free_port(), paused=True)
    page = Page(one.port)
    try:
        _wait(lambda: {"Playback", "Speed", "Scenario"} <= _labels(page))
        one.classroom.start_exercise("fastcat:inject:coupler:0x04")
        one.dashboard.scenario_player.load(load_scenario(PLAIN_FILE))
        _wait(lambda: PLAIN in _try(status, page) or "")
    finally:
        page.close()
        one.stop()
