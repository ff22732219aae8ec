"""Runs of repeated log rows, collapsed the way TwinCAT's logger shows them by repetition.

A master retrying a state change prints the same lines every 2.14 s (seed 000 §7.7: "'PREOP
to SAFEOP' failed! ..." then "state change aborted ..."); shown one by one they push the
emergency and the abnormal state change (the root cause) out of a bounded log within a
minute. Only the views collapse: the master's log and the events stay line by line.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

T = TypeVar("T")

# The longest group of lines repeated as a whole: a retry prints 2 rows in every log style.
MAX_PERIOD = 4


@dataclass
class Run(Generic[T]):
    first: T
    last: T
    count: int = 1


def collapse_repeats(items: Sequence[T], key: Callable[[T], Hashable],
                     max_period: int = MAX_PERIOD) -> list[Run[T]]:
    """``items`` oldest first -> runs oldest first. A group of 1..``max_period`` rows equal
    (by ``key``) to the last runs, in the same order, is added to them: A B A B A B gives
    A x3, B x3. A row in between breaks the run (A C A stays three rows), so no row moves
    past another."""
    runs: list[Run[T]] = []
    i = 0
    while i < len(items):
        for period in range(1, min(max_period, len(runs), len(items) - i) + 1):
            tail = runs[-period:]
            if all(key(items[i + j]) == key(run.first) for j, run in enumerate(tail)):
                for j, run in enumerate(tail):
                    run.last, run.count = items[i + j], run.count + 1
                i += period
                break
        else:
            runs.append(Run(items[i], items[i]))
            i += 1
    return runs


def repeat_suffix(count: int, first_stamp: str, last_stamp: str) -> str:
    """`` x12, last 14.52.31 949 ms``: how many times, and when the last one was, as the row's
    own Timestamp column reads (the TwinCAT stamp; its date only when it is not the first
    one's). Simulated seconds there ("last 52.3 s") read as "52 s ago" next to a wall-clock
    stamp."""
    if count < 2:
        return ""
    date, _, time = last_stamp.partition(" ")
    same_day = "/" in date and time and first_stamp.partition(" ")[0] == date
    return f" x{count}, last {time if same_day else last_stamp}"
