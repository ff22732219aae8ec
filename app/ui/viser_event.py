"""viser's message buffers: their wake-up event set only in viser's event-loop thread.

viser 1.1.1, ``viser/infra/_async_message_buffer.py``, ``AsyncMessageBuffer.push``:

    221        self.message_event.set()          # in the thread that writes a handle
    222        if self.atomic_counter == 0:
    229            self.event_loop.call_soon_threadsafe(self.message_event.set)

and ``atomic_end`` (line 251) schedules the same set on the loop when the outermost
``server.atomic()`` block ends. ``message_event`` is an ``asyncio.Event``, which is not
thread-safe: line 221 iterates its waiters in our dashboard thread (or viser's callback pool)
while the loop thread, in the window generator's ``await self.message_event.wait()`` (line
376), appends or removes its waiter future. The write then raises "deque mutated during
iteration"; and when the append lands during that iteration the flag is already set, so the
new waiter is never resolved, every later set() is a no-op, and the buffer's consumer (a
client's own buffer has one; the broadcast buffer one per browser) waits for good: that
browser gets no more updates (tests/app/test_viser_message_event.py).

The guard: each buffer's ``message_event`` is a :class:`LoopEvent`, whose set() outside its
loop's thread does nothing. viser schedules the real set on the loop for every push (line
229, or 251 after an atomic block), so the waiters are touched in the loop thread only. The
inline set served a synchronous reader of the flag; viser 1.1.1 has none (the window
generator reads it on the loop). Installed once, when ``app.ui`` is imported (before a
``ViserServer`` builds its broadcast buffer), for viser 1.1.1 only: another version's push()
must be read again before this is trusted (if it no longer scheduled the set, nothing would
be sent).
"""

from __future__ import annotations

import asyncio
import functools
import logging
from typing import Any

import viser
from viser.infra._async_message_buffer import AsyncMessageBuffer

logger = logging.getLogger(__name__)

VISER_VERSION = "1.1.1"  # the version whose push() / atomic_end() the guard relies on
_MARK = "_fieldrig_loop_event"


class LoopEvent(asyncio.Event):
    """An ``asyncio.Event`` whose set() counts only in ``loop``'s own thread."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__()
        self._owner_loop = loop

    def set(self) -> None:
        try:
            running: asyncio.AbstractEventLoop | None = asyncio.get_running_loop()
        except RuntimeError:  # a thread with no loop: the dashboard, viser's callback pool
            running = None
        # Off the loop (another loop's thread too: Playwright's in tests) viser's own
        # call_soon_threadsafe(set) follows, and sets it where the waiters live.
        if running is self._owner_loop:
            super().set()


def installed() -> bool:
    """True once new message buffers get a :class:`LoopEvent`."""
    return bool(getattr(AsyncMessageBuffer.__init__, _MARK, False))


def install() -> bool:
    """Give every message buffer built from now on a :class:`LoopEvent` (see the module).
    False, with a warning, on another viser version than the one read."""
    if viser.__version__ != VISER_VERSION:
        logger.warning("viser %s is not %s: its message buffers' wake-up event is left as it "
                       "is; read viser/infra/_async_message_buffer.py push() again "
                       "(app/ui/viser_event.py)", viser.__version__, VISER_VERSION)
        return False
    if installed():
        return True
    built = AsyncMessageBuffer.__init__

    @functools.wraps(built)
    def __init__(self: AsyncMessageBuffer, *args: Any, **kwargs: Any) -> None:
        built(self, *args, **kwargs)
        if "message_event" not in kwargs:  # one given by the caller is the caller's
            self.message_event = LoopEvent(self.event_loop)

    setattr(__init__, _MARK, True)
    AsyncMessageBuffer.__init__ = __init__  # type: ignore[method-assign]
    return True
