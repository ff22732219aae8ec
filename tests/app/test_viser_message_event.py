"""viser's message event set from a thread that is not its loop's (docs/dashboard.md
"Threading", app/ui/viser_event.py).

viser 1.1.1's ``AsyncMessageBuffer.push`` sets its ``asyncio.Event`` in the writing thread (our
dashboard thread, a callback's pool thread) while the loop thread may be appending its waiter
in ``Event.wait()``. The first test proves, with that order made certain (racing_loop.py), what
follows on a plain ``asyncio.Event``: the write raises "deque mutated during iteration" and the
buffer's only consumer is stranded for good, so that browser gets no more updates. The others
check the guard the dashboard installs: a write from any thread wakes the consumer.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Iterator

import pytest
import viser
from racing_loop import WAIT_S, HeldWaiters, LoopThread, message
from served_dashboard import local_server
from viser.infra._async_message_buffer import AsyncMessageBuffer

from app.ui import viser_event


@pytest.fixture
def loop() -> Iterator[LoopThread]:
    running = LoopThread()
    yield running
    running.stop()


def held_buffer(loop: LoopThread, event: asyncio.Event | None = None
                ) -> tuple[AsyncMessageBuffer, HeldWaiters]:
    """A per-client buffer (one consumer) whose consumer is held in its first wait()."""
    buffer = (AsyncMessageBuffer(loop.loop, persistent_messages=False) if event is None else
              AsyncMessageBuffer(loop.loop, persistent_messages=False, message_event=event))
    waiters = HeldWaiters(loop.thread)
    buffer.message_event._waiters = waiters  # type: ignore[attr-defined]
    loop.consume(buffer)
    assert waiters.appending.wait(WAIT_S)
    return buffer, waiters


def test_a_plain_event_set_off_its_loop_strands_the_consumer(loop: LoopThread) -> None:
    buffer, waiters = held_buffer(loop, asyncio.Event())  # viser's own, unguarded
    with pytest.raises(RuntimeError, match="deque mutated during iteration"):
        buffer.push(message(1))  # in the writer's thread, as the dashboard's write did
    buffer.push(message(2))  # a later write: both of its sets find the flag already set
    # Run on the loop after push(2)'s call_soon_threadsafe(set): the flag is set and the one
    # waiter unresolved. set() resolves waiters only when the flag was clear, and only the
    # consumer clears it, after its wait returned: no set() can wake it any more.
    flag, done = loop.call(lambda: (buffer.message_event.is_set(),
                                    [f.done() for f in waiters]))
    assert (flag, done) == (True, [False])
    assert buffer.message_counter == 2  # both messages are buffered, none is sent
    assert not loop.got.wait(0.3) and loop.received == []


def test_a_write_off_the_loop_wakes_the_consumer(loop: LoopThread) -> None:
    buffer, waiters = held_buffer(loop)
    buffer.push(message(1))  # raised "deque mutated during iteration" before the guard
    assert not waiters.proceed.is_set()  # the writer's thread never touched the waiters
    waiters.proceed.set()  # the loop thread's held append goes on
    assert loop.got.wait(WAIT_S)
    assert loop.received == [message(1)]


def test_a_write_in_an_atomic_block_is_sent_when_it_ends(loop: LoopThread) -> None:
    buffer, waiters = held_buffer(loop)
    buffer.atomic_start()  # server.atomic(), as every tick
    buffer.push(message(1))
    waiters.proceed.set()
    assert loop.call(lambda: [f.done() for f in waiters]) == [False]  # held by the block
    buffer.atomic_end()  # viser schedules the set on the loop here (push did not)
    assert loop.got.wait(WAIT_S)
    assert loop.received == [message(1)]


def test_a_write_on_the_loop_wakes_the_consumer(loop: LoopThread) -> None:
    buffer, waiters = held_buffer(loop)
    waiters.proceed.set()
    loop.call(lambda: buffer.push(message(1)))  # a coroutine callback's write
    assert loop.got.wait(WAIT_S)
    assert loop.received == [message(1)]


def test_the_served_buffers_have_the_guard() -> None:
    assert viser_event.installed()  # viser is the version whose push() was read
    with local_server() as server:
        broadcast = server._websock_server._broadcast_buffer
        assert isinstance(broadcast.message_event, viser_event.LoopEvent)
    # a per-client buffer is built by the same class: the guard is on its __init__
    loop = asyncio.new_event_loop()
    try:
        assert isinstance(AsyncMessageBuffer(loop, False).message_event, viser_event.LoopEvent)
    finally:
        loop.close()


def test_another_viser_version_is_not_guarded_blindly(
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.setattr(viser, "__version__", "9.9.9")
    with caplog.at_level(logging.WARNING, logger="app.ui.viser_event"):
        assert not viser_event.install()
    assert "9.9.9" in caplog.text and "_async_message_buffer" in caplog.text
