"""Who names the cause (docs/classroom.md "Exercises"): on a rig with a token the trainees
do. The instructor's page has the same Cause form (an open rig's instructor is everyone, and
must answer), and an instructor's *Name the cause* counted as the first answer: it knows the
hidden fault, its answer repaired it, and every trainee's answer was then refused."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from app.classroom.exercise import Phase
from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.panels.classroom_rig import ServedRig, serve_rig

TOKEN = "tok"
FAULT = "fastcat:inject:coupler:0x04"


class FakeClient:
    """What the classroom reads of a viser ClientHandle here: its id."""

    def __init__(self, client_id: int) -> None:
        self.client_id = client_id


def _serve(token: str | None) -> ServedRig:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    one = serve_rig(rig, Access(token), port=0, paused=True)
    one.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
    return one


@pytest.fixture
def served() -> Iterator[ServedRig]:
    one = _serve(TOKEN)
    yield one
    one.stop()


def test_the_instructor_s_answer_is_refused_a_trainee_s_counts(served: ServedRig) -> None:
    classroom = served.classroom
    instructor, trainee = FakeClient(7), FakeClient(8)
    assert classroom.access.present(instructor.client_id, TOKEN)
    exercise = classroom.start_exercise(FAULT, client=instructor)  # type: ignore[arg-type]
    assert exercise is not None
    client: Any = instructor
    with pytest.raises(PermissionError, match="the trainees name the cause"):
        classroom.name_cause(exercise.fault.cause, client)
    assert exercise.phase is Phase.RUNNING  # no answer recorded, the fault still injected
    assert classroom.name_cause(exercise.fault.cause, trainee) is True  # type: ignore[arg-type]
    assert exercise.phase is Phase.ANSWERED


def test_on_an_open_rig_the_instructor_answers() -> None:
    one = _serve(None)
    try:
        exercise = one.classroom.start_exercise(FAULT)
        assert exercise is not None
        client: Any = FakeClient(3)
        assert one.classroom.name_cause(exercise.fault.cause, client) is True
    finally:
        one.stop()
