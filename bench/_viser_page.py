"""A Python websocket client that viser counts as a page (benchmark 3's stand-in browser).

viser 1.1.1 lists a connection in ``ViserServer.get_clients()`` only once its first
``ViewerCameraMessage`` arrived (``_viser.py``: "a client is connected after the first camera
message"); a browser's viewer sends one as soon as its canvas has a size. The dashboard draws
nothing while that list is empty (app/ui/dashboard.py ``_run``), so a client that only
listens is sent the backlog and then nothing.

Both of benchmark 3's clients (bench/streaming.py, bench/_stream_clicks.py) connect and read
windows through here. tests/app/viser_page.py reads the same frames for the tests: bench does
not import tests, and app/ never reads its own frames (viser writes them), so neither owns a
shared decoder; it is three lines of viser 1.1.1's framing.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

VIEW = (1280, 720)  # the screenshots' viewport (app.screenshots.VIEWPORT)


def window(raw: bytes, unzip: Any) -> bytes:
    """The msgpack of one window: two 8-byte lengths, zstd msgpack, raw buffers."""
    size, packed = int.from_bytes(raw[:8], "little"), int.from_bytes(raw[8:16], "little")
    return bytes(unzip.decompress(raw[16:16 + packed], max_output_size=size))


def decode(raw: bytes, unzip: Any) -> list[dict[str, Any]]:
    """The messages of one window."""
    import msgspec

    return list(msgspec.msgpack.decode(window(raw, unzip))["messages"])


def encode(message: Any) -> bytes:
    """One message as a page sends it: msgpack of its fields and its type's name."""
    import msgspec

    return msgspec.msgpack.encode(message.as_serializable_dict())


async def say_hello(ws: Any) -> None:
    """Send the camera message a browser's viewer sends first: the server counts the page."""
    from viser._messages import ViewerCameraMessage

    await ws.send(encode(ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, -1.0, 1.0), fov=0.9, near=0.01, far=1000.0,
        image_height=VIEW[1], image_width=VIEW[0], look_at=(0.0, 0.0, 0.0),
        up_direction=(0.0, 0.0, 1.0))))


@asynccontextmanager
async def page(port: int) -> AsyncIterator[tuple[Any, bytes]]:
    """A page on the dashboard at ``port``: the websocket, counted by the server, and the first
    window it was sent (the backlog: the whole GUI and scene)."""
    import viser
    import websockets

    async with websockets.connect(f"ws://127.0.0.1:{port}",
                                  subprotocols=[f"viser-v{viser.__version__}"],
                                  max_size=None, compression=None) as ws:
        backlog = await ws.recv()
        await say_hello(ws)
        yield ws, backlog
