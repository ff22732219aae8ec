"""A viser message buffer on an event loop in a thread of its own, with a consumer that the
test can hold inside ``asyncio.Event.wait()`` (tests/app/test_viser_message_event.py).

The race in viser 1.1.1's ``AsyncMessageBuffer.push`` (docs/dashboard.md "Threading") needs
the loop thread to append its waiter while another thread's ``Event.set()`` iterates over the
waiters. ``HeldWaiters`` makes that order certain instead of lucky: the loop thread's first
append waits until a set() off the loop has started iterating (or the test lets it go), and
that iteration waits until the append is done.
"""

from __future__ import annotations

import asyncio
import collections
import threading
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

from viser import _messages
from viser.infra._async_message_buffer import AsyncMessageBuffer

T = TypeVar("T")
WAIT_S = 5.0


class HeldWaiters(collections.deque):  # type: ignore[type-arg]
    """An Event's ``_waiters``: the loop thread's first append is held (see the module)."""

    def __init__(self, loop_thread: threading.Thread) -> None:
        super().__init__()
        self._loop_thread = loop_thread
        self.appending = threading.Event()  # the loop thread is in wait(), about to append
        self.proceed = threading.Event()  # set by a set() iterating off the loop, or the test
        self.appended = threading.Event()
        self._armed = True

    def append(self, item: Any) -> None:
        if self._armed and threading.current_thread() is self._loop_thread:
            self._armed = False
            self.appending.set()
            self.proceed.wait(WAIT_S)
            super().append(item)
            self.appended.set()
            return
        super().append(item)

    def __iter__(self) -> Iterator[Any]:
        it = super().__iter__()  # taken before the append: the deque's mutation check
        if (threading.current_thread() is not self._loop_thread and self.appending.is_set()
                and not self.appended.is_set()):
            self.proceed.set()
            self.appended.wait(WAIT_S)
        return it


class LoopThread:
    """An event loop running in a thread of its own, and a buffer's consumer on it."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, name="viser-loop",
                                       daemon=True)
        self.thread.start()
        self.received: list[Any] = []
        self.got = threading.Event()

    def call(self, fn: Callable[[], T]) -> T:
        """``fn()`` run on the loop, after every callback already scheduled there."""
        async def run() -> T:
            return fn()
        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(WAIT_S)

    def consume(self, buffer: AsyncMessageBuffer) -> None:
        """Send every window of ``buffer`` to ``received``, as viser's producer would."""
        async def consumer() -> None:
            async for window in buffer.window_generator(0):
                self.received.extend(window)
                self.got.set()
        asyncio.run_coroutine_threadsafe(consumer(), self.loop)

    def stop(self) -> None:
        def cancel_all() -> None:
            for task in asyncio.all_tasks(self.loop):
                task.cancel()
        self.loop.call_soon_threadsafe(cancel_all)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(WAIT_S)
        if not self.thread.is_alive():
            self.loop.close()


def message(n: int) -> _messages.Message:
    """A GUI value update of its own element (no redundancy key shared with another)."""
    return _messages.GuiUpdateMessage(f"element-{n}", {"value": n})
