"""One exercise on one rig: a hidden fault, what the trainees did, their answer, the score.

Pure bookkeeping: the caller passes times (wall seconds: a trainee's speed is human time) and
the rig's snapshot; the UI (app/ui/panels/classroom.py) applies the fault and the repair
through the runtime. The flow (docs/classroom.md): the instructor starts an exercise with a
hidden fault; a trainee names a cause — the right one repairs the fault's cause, as a
technician's repair would, a wrong one changes nothing; the trainee resets what stays latched
and says "done"; the rig is then checked and the exercise scored.
"""

from __future__ import annotations

import enum
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from app.classroom.faults import Catalog, HiddenFault, fault_gone, other_faults
from app.classroom.scoring import RULES, Score, ScoringRules, score


class Phase(enum.Enum):
    RUNNING = "running"  # fault injected, waiting for an answer
    ANSWERED = "answered"  # cause named; the trainee may still reset things
    FINISHED = "finished"


@dataclass(frozen=True)
class Action:
    """A command one of the connections sent during the exercise."""

    at_s: float  # seconds since the start
    client_id: int | None
    role: str
    text: str
    refused: str = ""


@dataclass
class Exercise:
    fault: HiddenFault
    started_s: float
    rules: ScoringRules = RULES
    phase: Phase = Phase.RUNNING
    actions: list[Action] = field(default_factory=list)
    answer: str | None = None  # cause id
    answered_by: int | None = None
    answered_s: float | None = None
    finished_s: float | None = None
    fixed: bool | None = None
    others: list[str] = field(default_factory=list)  # other faults on the device at the end
    result: Score | None = None

    def __post_init__(self) -> None:
        self._lock = threading.Lock()

    @property
    def cause_right(self) -> bool:
        return self.answer == self.fault.cause

    def record(self, now_s: float, client_id: int | None, role: str, text: str,
               refused: str = "") -> None:
        with self._lock:
            if self.phase is not Phase.FINISHED:
                self.actions.append(Action(round(now_s - self.started_s, 3), client_id, role,
                                           text, refused))

    def name_cause(self, now_s: float, cause_id: str, client_id: int | None = None) -> bool:
        """Record the answer (the first one counts); True when it is the injected cause, i.e.
        when the caller should apply the fault's repair."""
        with self._lock:
            if self.phase is not Phase.RUNNING:
                raise ValueError("a cause was already named for this exercise")
            self.answer, self.answered_by = cause_id, client_id
            self.answered_s = round(now_s - self.started_s, 3)
            self.phase = Phase.ANSWERED
            return self.cause_right

    def finish(self, now_s: float, snapshot: Mapping[str, Any]) -> Score:
        """Check the rig and score; the exercise then records nothing more."""
        with self._lock:
            if self.phase is Phase.FINISHED and self.result is not None:
                return self.result
            self.finished_s = round(now_s - self.started_s, 3)
            self.fixed = fault_gone(self.fault, snapshot)
            self.others = other_faults(self.fault, snapshot)
            refused = sum(1 for a in self.actions if a.refused)
            self.result = score(cause_right=self.cause_right, fixed=self.fixed,
                                seconds=self.finished_s, actions=len(self.actions),
                                refused=refused, rules=self.rules,
                                named=self.answer is not None, others=self.others)
            self.phase = Phase.FINISHED
            return self.result

    def report(self, catalog: Catalog) -> dict[str, Any]:
        """A plain dict for the instructor's panel and for logs."""
        cause = catalog.cause(self.fault.cause)
        named = catalog.cause(self.answer) if self.answer else None
        return {
            "fault": self.fault.label, "cause": cause.label if cause else self.fault.cause,
            "phase": self.phase.value,
            "answer": named.label if named else self.answer, "right": self.cause_right,
            "answered_by": self.answered_by,
            "answered_s": self.answered_s, "finished_s": self.finished_s, "fixed": self.fixed,
            "others": list(self.others),
            "actions": [{"t": a.at_s, "client": a.client_id, "role": a.role, "text": a.text,
                         "refused": a.refused} for a in self.actions],
            "score": None if self.result is None else {
                "total": self.result.total, "maximum": self.result.maximum,
                "parts": [{"rule": p.rule, "points": p.points, "why": p.why}
                          for p in self.result.parts]},
        }
