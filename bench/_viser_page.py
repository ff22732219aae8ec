"""A Python websocket client that viser counts as a page (benchmark 3's stand-in browser).

viser 1.1.1 lists a connection in ``ViserServer.get_clients()`` only once its first
``ViewerCameraMessage`` arrived (``_viser.py``: "a client is connected after the first camera
message"); a browser's viewer sends one as soon as its canvas has a size. The dashboard draws
nothing while that list is empty (app/ui/dashboard.py ``_run``), so a client that only
listens is sent the backlog and then nothing.
"""

from __future__ import annotations

from typing import Any

VIEW = (1280, 720)  # the screenshots' viewport (app.screenshots.VIEWPORT)


def decode(raw: bytes, unzip: Any) -> list[dict[str, Any]]:
    """The messages of one window: two 8-byte lengths, zstd msgpack, raw buffers."""
    import msgspec

    size, packed = int.from_bytes(raw[:8], "little"), int.from_bytes(raw[8:16], "little")
    inner = unzip.decompress(raw[16:16 + packed], max_output_size=size)
    return list(msgspec.msgpack.decode(inner)["messages"])


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
