"""Event loops a test runs itself, each run in a thread of its own.

Playwright's sync API leaves its event loop marked running in the main thread once a browser
test has started it (tests/browser/conftest.py ``browser`` is session-wide), and asyncio
refuses to run a second loop in a thread that has one running: ``asyncio.run`` and
``loop.run_until_complete`` in the test's thread failed with "Cannot run the event loop while
another loop is running" whenever a browser test ran before, in the same pytest process. A
fresh thread has no running loop, whatever ran before; the test's thread waits for it.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Coroutine
from concurrent.futures import ThreadPoolExecutor
from typing import Any, TypeVar

T = TypeVar("T")


def in_own_thread(fn: Callable[[], T]) -> T:
    """``fn()`` in a fresh thread: its result, or its exception raised here."""
    with ThreadPoolExecutor(1, thread_name_prefix="own-loop") as pool:
        return pool.submit(fn).result()


def run(coro: Coroutine[Any, Any, T]) -> T:
    """``asyncio.run(coro)``, whatever loop the test's thread has running."""
    return in_own_thread(lambda: asyncio.run(coro))


def complete(loop: asyncio.AbstractEventLoop, awaitable: Awaitable[T]) -> T:
    """``loop.run_until_complete(awaitable)``, whatever loop the test's thread has running."""
    return in_own_thread(lambda: loop.run_until_complete(awaitable))
