"""How an exercise is scored: the rules are data (docs/classroom.md "Scoring").

A trainee earns points for naming the right cause, for leaving the rig without the fault, and
for being quick; loses points for commands beyond what the repair needed and for commands the
server refused (trying to inject, reset or load a scenario). The total never goes below 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class ScoringRules:
    cause_points: int = 50  # the named cause is the injected one
    fixed_points: int = 30  # the fault's code is gone and its repair holds at the end
    time_points: int = 20  # all of them up to ``par_s``, none from ``limit_s`` on
    par_s: float = 120.0
    limit_s: float = 600.0
    free_actions: int = 3  # commands a fix may take without penalty (e.g. reset, resync, run)
    per_extra_action: int = 1
    max_action_penalty: int = 10
    per_refused: int = 2
    max_refused_penalty: int = 10

    def __post_init__(self) -> None:
        if not 0 <= self.par_s < self.limit_s:
            raise ValueError("scoring needs 0 <= par_s < limit_s")

    @property
    def maximum(self) -> int:
        return self.cause_points + self.fixed_points + self.time_points


RULES = ScoringRules()


@dataclass(frozen=True)
class Part:
    rule: str
    points: int
    why: str


@dataclass(frozen=True)
class Score:
    total: int
    maximum: int
    parts: tuple[Part, ...]


def time_points(rules: ScoringRules, seconds: float) -> int:
    if seconds <= rules.par_s:
        return rules.time_points
    if seconds >= rules.limit_s:
        return 0
    left = (rules.limit_s - seconds) / (rules.limit_s - rules.par_s)
    return round(rules.time_points * left)


def score(*, cause_right: bool, fixed: bool, seconds: float, actions: int, refused: int,
          rules: ScoringRules = RULES, named: bool = True, others: Sequence[str] = ()) -> Score:
    """``actions``: commands the trainee's connections sent (refused ones included),
    ``refused``: how many of them the server refused; ``named``: a cause was named at all
    (an exercise the instructor ended before any answer); ``others``: other faults the
    device still has, named in the result but not the trainee's to fix."""
    still = f"; another fault is still present: {', '.join(others)}" if others else ""
    parts = [
        Part("cause", rules.cause_points if cause_right else 0,
             "named the injected cause" if cause_right
             else "named another cause" if named else "no cause named"),
        Part("fixed", rules.fixed_points if fixed else 0,
             ("the fault is gone" if fixed else "the rig still shows the fault") + still),
        Part("time", time_points(rules, seconds) if cause_right and fixed else 0,
             f"{seconds:.0f} s (par {rules.par_s:g} s, none from {rules.limit_s:g} s)"
             + ("" if cause_right and fixed else "; only counts for a right, working fix")),
    ]
    extra = max(0, actions - refused - rules.free_actions)
    if extra:
        parts.append(Part("actions", -min(rules.max_action_penalty,
                                          extra * rules.per_extra_action),
                          f"{extra} command(s) beyond {rules.free_actions}"))
    if refused:
        parts.append(Part("refused", -min(rules.max_refused_penalty, refused * rules.per_refused),
                          f"{refused} refused command(s)"))
    total = max(0, sum(p.points for p in parts))
    return Score(total, rules.maximum, tuple(parts))
