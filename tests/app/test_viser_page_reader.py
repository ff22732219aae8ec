"""The classroom tests' Page (a browser as viser's server sees it) reads its websocket in a
thread of its own. An exception there stopped the thread without a word: the page got no more
messages and the test failed later as a lost update or a timeout that pointed nowhere. The
reader's error now fails the test at the page's next read, and at the fixture's teardown.
A websocket server of the test's own stands in for viser's and sends what it is told to."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from typing import Any

import msgspec
import pytest
import zstandard
from viser_page import Page, wait
from websockets.exceptions import ConnectionClosed
from websockets.sync.server import ServerConnection, serve


def viser_frame(messages: list[dict[str, Any]]) -> bytes:
    """A message bundle as viser's server sends it: sizes (8 bytes each, little-endian) and
    the zstd-packed msgpack."""
    inner = msgspec.msgpack.encode({"messages": messages})
    packed = zstandard.ZstdCompressor().compress(inner)
    return len(inner).to_bytes(8, "little") + len(packed).to_bytes(8, "little") + packed


@contextmanager
def websocket_server(handler: Callable[[ServerConnection], None]) -> Iterator[int]:
    """A websocket server on 127.0.0.1 running ``handler`` per connection; yields its port."""
    with serve(handler, "127.0.0.1", 0) as server:
        thread = threading.Thread(target=server.serve_forever, daemon=True)
        thread.start()
        try:
            yield server.socket.getsockname()[1]
        finally:
            server.shutdown()
            thread.join(5)


def server_sending(*frames: bytes | str) -> AbstractContextManager[int]:
    """A server that sends ``frames`` to whoever connects, then keeps the connection open
    until the page closes it."""
    def handler(ws: ServerConnection) -> None:
        for frame in frames:
            ws.send(frame)
        for _ in ws:  # the page's camera message, then nothing until it closes
            pass

    return websocket_server(handler)


def test_messages_a_page_reads_are_kept() -> None:
    """The server's framing as the page decodes it (without this the tests below could pass
    on a server whose every frame makes the reader raise)."""
    sent = [{"type": "GuiUpdateMessage", "uuid": "a", "updates": {"value": 1}}]
    with server_sending(viser_frame(sent)) as port:
        page = Page(port)
        try:
            assert wait(page.received) == sent
        finally:
            page.close()
        page.check()  # closed by the test: no error


@pytest.mark.parametrize("frame, error", [
    ("a text frame", AssertionError),  # viser sends bytes only
    (b"\x10" + bytes(7) + b"\x04" + bytes(7) + b"junk", zstandard.ZstdError),
], ids=["text", "bad-zstd"])
def test_an_exception_in_the_reader_fails_the_next_read(frame: bytes | str,
                                                        error: type[Exception]) -> None:
    with server_sending(frame, viser_frame([{"type": "After"}])) as port:
        page = Page(port)
        try:
            with pytest.raises(AssertionError, match="reader thread raised") as raised:
                wait(lambda: page.received() and False, timeout=5.0)
            assert isinstance(raised.value.__cause__, error)  # its traceback with it
            with pytest.raises(AssertionError, match="reader thread raised"):
                page.check()  # what a fixture calls at teardown
        finally:
            page.close()


def test_a_page_the_server_dropped_fails_the_next_read() -> None:
    """A test waiting for an update on a page viser closed would only time out."""
    def handler(ws: ServerConnection) -> None:
        ws.recv()  # the page's camera message
        ws.close()

    with websocket_server(handler) as port:
        page = Page(port)
        try:
            with pytest.raises(AssertionError, match="reader thread raised") as raised:
                wait(lambda: page.received() and False, timeout=5.0)
            assert isinstance(raised.value.__cause__, ConnectionClosed)
        finally:
            page.close()
