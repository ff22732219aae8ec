"""Where a scenario load starts a new run in a batch of journalled events.

A load (Play, Restart, an exercise: app/player.py) makes the rig factory-fresh with the clock
at 0, and the views that keep rows of a run (the event log, the Codes tab's Reported list, the
Drive tab's log) start afresh there. The clock going back does not tell them: a load while it
is still at 0 s (Restart before Play, another scenario picked before time moved) puts nothing
back, and the old run's rows stayed. The Player counts loads and notes the journal's sequence
number at each; a view's batch (``Runtime.events_since``) is split at that number, so the old
run's events taken in the same batch stay out of the new run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from devices.events import Event

# (generation, journal sequence number at that load): Player.last_load
LastLoad = Callable[[], tuple[int, int]]


class RunSplitter:
    """One per reader of the journal (each reads its own batches)."""

    def __init__(self, last_load: LastLoad) -> None:
        self._last_load = last_load
        self._generation = last_load()[0]

    def split(self, seq: int, events: Sequence[Event]
              ) -> tuple[list[Event], list[Event]] | None:
        """``seq``, ``events``: what ``events_since`` just returned (read before this call,
        so a load between the two is seen now, its events in the next batch). None when no
        load happened since the last call; else (the old run's events, the new run's)."""
        generation, load_seq = self._last_load()
        if generation == self._generation:
            return None
        self._generation = generation
        # The batch is the journal's tail up to ``seq``, numbered without gaps.
        cut = min(max(load_seq - (seq - len(events)), 0), len(events))
        return list(events[:cut]), list(events[cut:])
