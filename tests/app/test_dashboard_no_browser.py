"""The dashboard's thread computes no view while no browser is connected (that was most of an
idle served rig's dashboard cost), yet loses nothing: the logs take every event meanwhile, and
the first update with a browser there shows the current frame and those events."""

from __future__ import annotations

import time
from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard

TIMEOUT_S = 60


def wait_for(condition: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + TIMEOUT_S
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.02)


def test_no_view_is_computed_without_a_browser_and_nothing_is_lost() -> None:
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    runtime.set_paused(True)  # frames only when the test advances
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    dashboard = Dashboard(server, runtime)
    queued: list[Any] = []
    queue = server._websock_server.queue_message

    def recorded(message: Any) -> None:
        queued.append(message)
        queue(message)
    server._websock_server.queue_message = recorded  # type: ignore[method-assign]
    clients: dict[int, Any] = {}
    server.get_clients = lambda: clients  # type: ignore[method-assign]
    runtime.start()
    dashboard.start()
    try:
        runtime.advance(6_000_000).result(timeout=TIMEOUT_S)  # power-on, scan, walk to OP
        runtime.command("fastcat/2", "unplug", {}).result(timeout=TIMEOUT_S)
        runtime.advance(100_000).result(timeout=TIMEOUT_S)
        # The thread has taken the events (the runtime's journal is bounded) ...
        wait_for(lambda: dashboard._event_seq == runtime.events_since(0)[0],
                 "the dashboard took the events")
        time.sleep(0.2)  # ... and had every chance to draw a view
        assert queued == []
        # A browser connects (the connect callback wakes the thread); it takes attributes
        # as a ClientHandle does (page_ready marks it).
        clients[1] = SimpleNamespace(client_id=1)
        dashboard._wake.set()
        wait_for(lambda: any("alarm 0x04" in str(getattr(m, "updates", "")) for m in queued),
                 "the log shows the alarm raised while no browser was there")
        shown = f"t = {runtime.frame.t_us // 100_000 / 10:.1f} s"
        wait_for(lambda: any(shown in str(getattr(m, "updates", "")) for m in queued),
                 "the state panel shows the current frame's time")
    finally:
        dashboard.stop()
        runtime.stop()
        server.stop()
