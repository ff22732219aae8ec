"""Exercise files (docs/classroom.md "Exercise files"): a scenario sets the stage, its
``[exercise]`` table names the hidden fault injected at a simulated time."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.classroom.exercise_file import ExerciseSpec, load_exercise, parse_spec, split_exercise
from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError, parse_scenario
from app.ui.panels.classroom_rig import ServedRig, serve_rig

FILE = """\
[scenario]
name = "Lost node on a running line"
duration_s = 4

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true

[exercise]  # the hidden fault
fault = "fastcat:inject:coupler:0x04"
at_s = 3.0

[[step]]
at = 1.0
caption = "The line runs."
"""


def test_split_keeps_the_scenario() -> None:
    rest, table = split_exercise(FILE)
    assert table == {"fault": "fastcat:inject:coupler:0x04", "at_s": 3.0}
    scenario = parse_scenario(rest)
    assert scenario.name == "Lost node on a running line" and len(scenario.steps) == 2
    assert split_exercise("[scenario]\nname = 'x'\n") == ("[scenario]\nname = 'x'\n", None)


@pytest.mark.parametrize(("table", "spec"), [
    ({"fault": "f"}, ExerciseSpec("f")),
    ({"fault": "f", "module": 3, "at_s": 2}, ExerciseSpec("f", 3, 2.0)),
])
def test_spec(table: dict[str, object], spec: ExerciseSpec) -> None:
    assert parse_spec(table) == spec


@pytest.mark.parametrize("table", [
    {}, {"fault": ""}, {"fault": "f", "module": 0}, {"fault": "f", "module": True},
    {"fault": "f", "at_s": -1}, {"fault": "f", "when": 1}])
def test_bad_spec(table: dict[str, object]) -> None:
    with pytest.raises(ScenarioError, match="exercise"):
        parse_spec(table)


def test_a_typo_in_an_exercise_key_says_what_was_meant() -> None:
    with pytest.raises(ScenarioError, match=r"exercise\.modul: unknown key .*; did you mean "
                                            r"'module'\?$"):
        parse_spec({"fault": "f", "modul": 2})


def test_inline_table_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "x.toml"
    path.write_text('exercise = { fault = "f" }\n[scenario]\nname = "x"\n')
    with pytest.raises(ScenarioError, match="one \\[exercise\\] table"):
        load_exercise(path)


def run_until_started(served: ServedRig, run_us: int) -> None:
    """After Play file and start: ``run_us`` of simulated time, then wait for the classroom's
    thread to start the exercise (its hidden fault injected)."""
    served.runtime.advance(run_us).result(timeout=60)
    deadline = time.monotonic() + 10
    while served.classroom.exercise is None:
        assert time.monotonic() < deadline, "the exercise did not start"
        time.sleep(0.05)


@pytest.fixture
def served(tmp_path: Path) -> Iterator[ServedRig]:
    path = tmp_path / "lost_node.toml"
    path.write_text(FILE)
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    one = serve_rig(rig, Access(None), port=0, paused=True, exercise_files=[path])
    yield one
    one.stop()


def test_file_plays_then_injects(served: ServedRig, tmp_path: Path) -> None:
    classroom = served.classroom
    at = classroom.start_from_file(tmp_path / "lost_node.toml")
    assert at == 3_000_000 and classroom.exercise is None
    run_until_started(served, 3_500_000)
    assert classroom.exercise.fault.id == "fastcat:inject:coupler:0x04"
    snap = served.runtime.submit(served.runtime.rig.snapshot).result(timeout=10)
    assert snap["devices"]["fastcat"]["injected"]


def test_refused_commands_start_afresh_with_each_exercise(served: ServedRig) -> None:
    """The instructor's list mixed refusals from before the exercise and from earlier ones."""
    classroom = served.classroom
    classroom.refusals.append("#3 fastcat: power makes a fault (instructor only)")
    classroom.start_exercise("fastcat:inject:coupler:0x04")
    assert list(classroom.refusals) == []


ENDS_WITH_THE_FAULT = """\
[scenario]
name = "Line in OP"
duration_s = 1

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true

[exercise]
fault = "fastcat:inject:coupler:0x04"
at_s = 1.0
"""


def test_the_rig_runs_on_after_the_file_so_the_fault_shows(tmp_path: Path) -> None:
    """The fault goes in at the file's last instant: the player paused the rig at the
    scenario's end, so the clock stood at 1 s, the coupler never reported the fault and the
    exercise timer ran on over a rig that showed nothing. The rig here is as served: running,
    its clock not advanced by hand."""
    path = tmp_path / "ends_with_the_fault.toml"
    path.write_text(ENDS_WITH_THE_FAULT)
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    one = serve_rig(rig, Access(None), port=0, exercise_files=[path])
    try:
        assert not one.runtime.paused
        one.classroom.start_from_file(path)
        deadline = time.monotonic() + 30
        while True:
            snap = one.runtime.submit(one.runtime.rig.snapshot).result(timeout=10)
            fastcat = snap["devices"]["fastcat"]
            if one.classroom.exercise is not None and fastcat["fault_active"]:
                break
            assert time.monotonic() < deadline, (
                f"no fault shown: t={one.runtime.frame.t_us} us, paused="
                f"{one.runtime.paused}, exercise={one.classroom.exercise is not None}")
            time.sleep(0.1)
        assert fastcat["alarm"]["code"] == 0x04
        assert not one.runtime.paused and one.runtime.frame.t_us > 1_000_000
    finally:
        one.stop()


class _Client:
    """What the panel's notification path writes to (viser's ClientHandle.add_notification)."""

    client_id = 7

    def __init__(self) -> None:
        self.notes: list[tuple[str, str, str]] = []

    def add_notification(self, title: str, body: str, color: str, **_: object) -> None:
        self.notes.append((title, body, color))


@pytest.mark.parametrize(("fault", "said"), [
    ("fastcat:inject:module:0x0B", "module alarm (§7.6): target 'fastcat/N'; give its module"),
    ("cpx:inject:fault:module_failure", "module_failure needs a module: target 'cpx/N'"),
])
def test_a_file_edited_after_the_start_is_checked_at_play(served: ServedRig, tmp_path: Path,
                                                          fault: str, said: str) -> None:
    """Play file and start looked the fault id up only: a file edited after the server's
    start check played its scenario and failed in the injection thread (a logged warning, the
    exercise silently without its fault). Now it is refused, nothing loaded, with one line."""
    path = tmp_path / "lost_node.toml"
    path.write_text(FILE.replace("fastcat:inject:coupler:0x04", fault))
    classroom, player = served.classroom, served.classroom._player.player
    generation = player.view().generation
    client = _Client()
    play = lambda: classroom.start_from_file(path)  # noqa: E731
    classroom._guarded(client, play, "started")  # type: ignore[arg-type]
    [(title, body, color)] = client.notes
    assert (title, color) == ("Exercise", "red")
    assert said in body and body.startswith(f"{path}: [exercise] fault"), body
    assert "\n" not in body
    assert player.view().generation == generation and served.runtime.paused
    assert classroom.exercise is None


def test_the_scenario_tab_after_an_exercise_file(served: ServedRig, tmp_path: Path) -> None:
    """After the file's scenario ended, Play and Restart in the Scenario tab reloaded the file
    as a plain scenario and were refused with "exercise: unknown key (a scenario has
    [scenario], [[step]] and [[on]] tables)". Play now goes on with the loaded file (the rig
    runs on, as Play file and start left it); Restart, which would reset the rig under the
    running exercise without its hidden fault, is refused with one line naming the way."""
    path = tmp_path / "lost_node.toml"
    classroom = served.classroom
    panel = classroom._player
    classroom.start_from_file(path)
    run_until_started(served, 4_500_000)
    generation = panel.player.view().generation
    panel.player.pause()
    client = _Client()
    panel._run(client, "Play")  # type: ignore[arg-type]
    assert client.notes == [] and not served.runtime.paused
    assert panel.player.view().generation == generation
    panel._run(client, "Restart")  # type: ignore[arg-type]
    [(title, body, color)] = client.notes
    assert (title, color) == ("Scenario: Restart refused", "red")
    assert "\n" not in body and "lost_node.toml" in body and "exercise file" in body \
        and "Play file and start" in body, body
    assert panel.player.view().generation == generation
    assert classroom.exercise is not None and classroom.exercise.phase.name == "RUNNING"


def test_an_exercise_file_read_as_a_scenario_says_what_it_is(tmp_path: Path) -> None:
    """`scenario run` or the Scenario tab on an exercise file said only "exercise: unknown
    key": the file is not broken, it is played another way."""
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(FILE, "ex.toml")
    said = str(caught.value)
    assert said.startswith("ex.toml: [exercise]: an exercise file") and "\n" not in said
    assert "Play file and start" in said and "--exercises" in said, said
