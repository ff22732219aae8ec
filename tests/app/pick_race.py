"""Holds for the race tests of a per-page form written by two threads: a pick's callback
(viser's thread pool) and the dashboard's frame update (its own thread). One writer is held
between its read and its write while the other writes; no sleep decides who goes first.

:class:`HeldProp` holds a thread at a PageProp's ``show`` (after it read the pick and the
frame, before it writes). :class:`SpyLock` stands in for a form's lock and tells when the
other writer waits on it: with the lock, the other writer cannot write while one is held, and
the test goes on once it waits; without it, the test goes on once the other writer is done.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable
from typing import Any

DASHBOARD = "fieldrig-dashboard"  # the dashboard thread's name (Dashboard.start)
HOLD_S = 10.0


def on_dashboard() -> bool:
    return threading.current_thread().name == DASHBOARD


def off_dashboard() -> bool:
    return not on_dashboard()


class HeldProp:
    """A PageProp as one thread sees it: once ``armed``, that thread's next ``show`` waits for
    ``release`` before it writes (``after``: once it wrote, before the rest of its update)."""

    def __init__(self, real: Any, thread: Callable[[], bool], after: bool = False) -> None:
        self._real, self._thread, self._after_write = real, thread, after
        self.armed, self.entered, self.release = False, threading.Event(), threading.Event()

    def show(self, value_for: Callable[[int], Any]) -> None:
        if self._after_write:
            self._real.show(value_for)
        if self.armed and self._thread():
            self.armed = False
            self.entered.set()
            assert self.release.wait(HOLD_S), "never released"
        if not self._after_write:
            self._real.show(value_for)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)


class SpyLock:
    """A (reentrant) lock that sets ``waiting`` when a thread ``thread`` picks asks for it.
    Never cleared: that thread may have asked (and be waiting) before the test looks, and
    going on early is harmless with the lock (the writers take turns whatever the order)."""

    def __init__(self, thread: Callable[[], bool]) -> None:
        self._lock, self._thread = threading.RLock(), thread
        self.waiting = threading.Event()

    def __enter__(self) -> bool:
        if self._thread():
            self.waiting.set()
        return self._lock.acquire()

    def __exit__(self, *_exc: object) -> None:
        self._lock.release()


def inside(thread: threading.Thread, function: str) -> bool:
    """``thread`` runs ``function`` now (somewhere in its stack): a pick's callback, whose
    function viser holds bound since the form was built, so no wrapper can tell its end."""
    frame = sys._current_frames().get(thread.ident or -1)
    while frame is not None:
        if frame.f_code.co_name == function:
            return True
        frame = frame.f_back
    return False
