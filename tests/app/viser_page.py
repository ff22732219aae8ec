"""A browser as viser's server sees it, for the classroom tests: a websocket connection that
keeps every message viser sends it, read by a thread of its own.

An exception in that reader thread (a frame it cannot decode, the server dropping the page)
is kept and raised in the test's thread, by the page's next read (:meth:`Page.received`,
through which every lookup goes) or by :meth:`Page.check`, which fixtures call at teardown.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import msgspec
import viser
import zstandard
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

Vector = tuple[float, float, float]


def wait(predicate: Any, timeout: float = 20.0) -> Any:
    """``predicate()``'s first true value, polled; fails after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while not (value := predicate()):
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)
    return value


class Page:
    """A browser as viser's server sees it: a websocket; keeps every message it receives."""

    def __init__(self, port: int, position: Vector = (0.0, -5.0, 1.0),
                 look_at: Vector = (0.0, 0.0, 0.0)) -> None:
        self._ws = connect(f"ws://127.0.0.1:{port}",
                           subprotocols=[f"viser-v{viser.__version__}"])  # type: ignore[list-item]
        self.messages: list[dict[str, Any]] = []
        self._lock = threading.Lock()
        self._closing = False
        self._error: BaseException | None = None
        threading.Thread(target=self._read, daemon=True).start()
        # viser counts a connection as a client from its first camera message.
        self.report_camera(position, look_at)

    def report_camera(self, position: Vector, look_at: Vector) -> None:
        """The camera message a browser sends after its camera moved (a 1280 x 720 canvas;
        the orientation is not read by the dashboard)."""
        self._ws.send(msgspec.msgpack.encode({
            "type": "ViewerCameraMessage", "wxyz": (1.0, 0.0, 0.0, 0.0),
            "position": tuple(map(float, position)), "fov": 0.9, "near": 0.01, "far": 100.0,
            "image_height": 720, "image_width": 1280, "look_at": tuple(map(float, look_at)),
            "up_direction": (0.0, 0.0, 1.0)}))

    def _read(self) -> None:
        unzip = zstandard.ZstdDecompressor()
        try:
            while True:
                frame = self._ws.recv()
                assert isinstance(frame, bytes)
                size = int.from_bytes(frame[:8], "little")
                packed = int.from_bytes(frame[8:16], "little")
                inner = unzip.decompress(frame[16:16 + packed], max_output_size=size)
                with self._lock:
                    self.messages += msgspec.msgpack.decode(inner)["messages"]
        except ConnectionClosed as closed:
            if not self._closing:  # the server dropped the page: later reads would wait on
                self._error = closed  # messages that can no longer come
        except BaseException as exc:
            # Kept for the test's thread: raised here it would only stop this thread, and the
            # test would fail later as a lost update or a timeout that points nowhere.
            self._error = exc

    def check(self) -> None:
        """Fail with the reader thread's exception (as the cause) if it died of one."""
        if self._error is not None:
            raise AssertionError(f"the page's reader thread raised {self._error!r}") \
                from self._error

    def received(self) -> list[dict[str, Any]]:
        self.check()
        with self._lock:
            return list(self.messages)

    def widget(self, label: str, option: str | None = None) -> str:
        """The uuid of a widget this page got, by label (and one of its options)."""
        for m in self.received():
            props = m.get("props") or {}
            if props.get("label") == label and (option is None
                                                or option in (props.get("options") or ())):
                return str(m["uuid"])
        raise KeyError(label)

    def last(self, label: str | None, option: str) -> str:
        """The uuid of the newest widget offering ``option`` (and labelled ``label``): an
        instructor's own copy comes after the shared widget of the same label."""
        for m in reversed(self.received()):
            props = m.get("props") or {}
            if (label is None or props.get("label") == label) \
                    and option in (props.get("options") or ()):
                return str(m["uuid"])
        raise KeyError(option)

    def own(self, other: Page, label: str | None, option: str) -> str:
        """The uuid of this page's own widget (one ``other`` never got: shared widgets have
        the same uuid on every page) offering ``option`` and labelled ``label``, waiting for
        it to arrive: per-client widgets are built on viser's thread after the promote, and on
        a loaded machine the newest widget by that label can still be the shared one.

        ``option`` is one the widget offers now: a copy built before the server knew its
        options (an instructor's Module picker before the rail's first frame) gets them by a
        later update, not in its creation message."""
        def find() -> str | None:
            shared = {m.get("uuid") for m in other.received() if "props" in m}
            labels: dict[str, Any] = {}
            offered: dict[str, tuple[Any, ...]] = {}  # own widgets in creation order
            for m in self.received():
                uuid = m.get("uuid")
                if uuid in shared:
                    continue
                if "props" in m:
                    labels[uuid] = m["props"].get("label")
                    offered[uuid] = tuple(m["props"].get("options") or ())
                elif uuid in offered and m.get("type") == "GuiUpdateMessage" \
                        and "options" in (m.get("updates") or {}):
                    offered[uuid] = tuple(m["updates"]["options"] or ())
            for uuid in reversed(offered):
                if (label is None or labels[uuid] == label) and option in offered[uuid]:
                    return str(uuid)
            return None
        return str(wait(find))

    def updates(self, uuid: str) -> list[Any]:
        """The values the server later set on one widget of this page."""
        return [m["updates"]["value"] for m in self.received()
                if m.get("type") == "GuiUpdateMessage" and m.get("uuid") == uuid
                and "value" in (m.get("updates") or {})]

    def set(self, uuid: str, value: Any) -> None:
        """What the browser sends when its user changes a widget (or clicks a button)."""
        self._ws.send(msgspec.msgpack.encode(
            {"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": value}}))

    def close(self) -> None:
        self._closing = True
        self._ws.close()
