"""The hint of every "unknown X" message: the allowed name a typo was meant to be.

A rig file's key, a scenario's key or ``[[on]]`` event, a device, an action, an argument, a
module type, a fault symbol: each refusal lists what is allowed, and ends with
:func:`did_you_mean` so that one slip reads the same wherever it is made.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

# difflib's default: "slav" for "slave" and "DB17" for "DB16" are slips; "wheels" for
# "node_id" is not, and a guess there would only mislead.
CUTOFF = 0.6


def close_names(name: str, known: Iterable[str], n: int = 1,
                cutoff: float = CUTOFF) -> list[str]:
    """The ``known`` names closest to ``name``, best first, as ``known`` spells them; the
    comparison ignores case (``db16`` is a slip of ``DB16``), and ``name`` itself is none."""
    spelled: dict[str, str] = {}
    for one in known:
        spelled.setdefault(str(one).lower(), str(one))
    wanted = str(name).lower()
    if wanted in spelled and spelled[wanted] == name:
        return []
    found = difflib.get_close_matches(wanted, list(spelled), n=n, cutoff=cutoff)
    if wanted in spelled:  # only the case differs: that is the slip, whatever else is near
        found = [wanted, *(f for f in found if f != wanted)][:n]
    return [spelled[f] for f in found]


def closest_slip(names: Iterable[str], known: Iterable[str]) -> str | None:
    """The one of ``names`` that is most like one of ``known`` (a slip, as :func:`close_names`
    judges), the first on a tie; None when none is a slip. Which of a table's unknown keys to
    name: ``actoin`` of ``actoin`` and ``active`` (an argument) is the slip of ``action``."""
    allowed = [str(one) for one in known]
    best, score = None, 0.0
    for name in names:
        found = close_names(name, allowed)
        if not found:
            continue
        ratio = difflib.SequenceMatcher(None, str(name).lower(), found[0].lower()).ratio()
        if ratio > score:
            best, score = name, ratio
    return best


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """``"; did you mean 'slave'?"`` when ``name`` is a slip of one of ``known``, else ``""``:
    appended to an "unknown X" message after its list of what is allowed."""
    found = close_names(name, known)
    return f"; did you mean {found[0]!r}?" if found else ""
