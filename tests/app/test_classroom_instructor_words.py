"""The instructor's page speaks to the instructor and names trainees (docs/classroom.md
"Exercises", "Who did what").

Its Exercise box read the trainee's words ("When the instructor starts one, ...", "The
instructor has your result.") and its lists named trainees by viser's connection number
("12 s #11 fastcat: ..."), which no one in the room knows. The instructor's box now says what
the instructor does and where the result is; trainees are "trainee 1", "trainee 2", ... in the
order they first act, and each trainee's page says which one it is."""

from __future__ import annotations

import re
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import pytest
from test_classroom_leak import TOKEN

from app.classroom.roles import Access, Role
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.commands import Sent
from app.ui.panels.classroom_html import instructor_html, trainee_html
from app.ui.panels.classroom_rig import ServedRig, serve_rig

FAULT = "fastcat:inject:coupler:0x01"
TRAINEE_WORDS = ("When the instructor starts", "The instructor has your result",
                 "Another trainee")


def report(phase: str, **more: Any) -> dict[str, Any]:
    return {"phase": phase, "fault": "fastcat 0x01", "cause": "MODULE_CHANGED",
            "answer": None, "answered_by": None, "right": None, "answered_s": None,
            "fixed": None, "actions": [], "score": None, **more}


@pytest.mark.parametrize("phase", [None, "running", "answered", "finished"])
def test_the_instructors_exercise_box_speaks_to_the_instructor(phase: str | None) -> None:
    shown = trainee_html(None if phase is None else report(phase), 7.0, mine=False,
                         audience="instructor")
    assert not [w for w in TRAINEE_WORDS if w in shown], shown
    assert "Instructor folder" in shown, shown  # where the instructor starts and reads it


def test_an_open_rig_answers_and_reads_its_result_itself() -> None:
    """On an open rig every page is the instructor and names the cause too."""
    shown = trainee_html(report("finished"), 7.0, audience="open")
    assert "The instructor has your result" not in shown
    assert "Instructor folder" in shown
    assert "Another page" in trainee_html(report("answered"), 7.0, mine=False,
                                          audience="open")


def test_a_trainees_box_is_unchanged_but_names_the_trainee() -> None:
    shown = trainee_html(None, 0.0, name="trainee 2")
    assert "When the instructor starts one" in shown
    assert "trainee 2" in shown


@pytest.fixture
def served() -> Iterator[ServedRig]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    served = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    try:
        yield served
    finally:
        served.stop()


def test_the_instructors_lists_name_trainees_in_the_order_they_act(served: ServedRig) -> None:
    panel = served.classroom
    assert panel.start_exercise(FAULT) is not None
    panel._on_sent(Sent(11, Role.TRAINEE, "fastcat", "inject_fault", {"code": 1},
                        refused="instructor only"))
    panel._on_sent(Sent(7, Role.TRAINEE, "fastcat", "reset_fault"))
    panel._on_sent(Sent(11, Role.TRAINEE, "fastcat", "reset_fault"))
    panel.name_cause("fastcat:coupler:0x01", SimpleNamespace(client_id=7))  # type: ignore[arg-type]
    rep = panel.exercise.report(panel.catalog)  # type: ignore[union-attr]
    shown = instructor_html(rep, 9.0, list(panel.refusals), panel.names)
    assert not re.search(r"#\d", shown), shown
    assert [a["client"] for a in rep["actions"]] == [11, 7, 11]
    assert re.findall(r"s (trainee \d) fastcat", shown) == ["trainee 1", "trainee 2",
                                                             "trainee 1"], shown
    assert "trainee 1 fastcat: instructor only" in shown, shown  # the refused command
    assert "by trainee 2" in shown, shown  # the answer
    assert panel.names.get(7) == "trainee 2"
