"""What the browser benchmarks share: headless Chromium, servers in child processes, and the
default rig live behind the dashboard.

- Chromium: Debian's, through Playwright, launched as the screenshot CLI does
  (``app.screenshots.launch``: software WebGL, no network chatter, a private home); never a
  Playwright download.
- :class:`ServerProcess`: a benchmark's server runs as ``python -m bench.NAME serve ...`` in
  a process of its own (its threads do not share a GIL with the measuring side), says
  ``ready`` on stdout, and stops when its stdin closes.
- :func:`serve_dashboard`: the default rig at real-time speed behind the dashboard, powered
  on as ``python -m app`` starts it; what benchmarks 2 and 3 measure.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from app.screenshots import CHROMIUM, VIEWPORT, free_port, launch

__all__ = ["CHROMIUM", "VIEWPORT", "ServerProcess", "chromium", "free_port", "serve_dashboard"]

ROOT = Path(__file__).resolve().parent.parent
READY = "ready"


@contextmanager
def chromium() -> Iterator[Any]:
    """A headless Chromium browser (Playwright) in a home of its own, as the screenshot CLI
    launches it (``app.screenshots.launch``: a benchmark run leaves nothing in ``~``); closed
    on exit."""
    from playwright.sync_api import sync_playwright

    if not Path(CHROMIUM).exists():
        raise RuntimeError(f"{CHROMIUM} is missing (apt-get install chromium)")
    with sync_playwright() as pw:
        browser, remove_home = launch(pw)
        try:
            yield browser
        finally:
            try:
                browser.close()
            finally:
                remove_home()


class ServerProcess:
    """``python -m MODULE serve ARGS...`` on a free port (the port is the first argument)."""

    def __init__(self, module: str, *args: str, what: str = "server",
                 cwd: Path = ROOT) -> None:
        """``cwd``: the checkout whose code serves (another worktree, to compare trees)."""
        self.port = free_port()
        self.proc = subprocess.Popen([sys.executable, "-m", module, "serve", str(self.port),
                                      *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, cwd=cwd)
        assert self.proc.stdout is not None
        for line in self.proc.stdout:  # viser prints its banner first
            if line.strip() == READY:
                break
        else:
            self.close()
            raise RuntimeError(f"the {what} did not start")

    def url(self, query: str = "") -> str:
        return f"http://127.0.0.1:{self.port}/{query}"

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        try:
            self.proc.wait(15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def serve_until_stdin_closes(stop: Callable[[], None]) -> None:
    """The child's side of :class:`ServerProcess`: say ready, run until stdin closes."""
    print(READY, flush=True)
    sys.stdin.read()
    stop()


def serve_dashboard(port: int, dashboard_cls: Any = None,
                    setup: Callable[[Any, Any, Any], None] | None = None) -> None:
    """Serve the default rig behind ``dashboard_cls`` (default: the dashboard as shipped) on
    ``port`` until stdin closes. ``setup(rig, runtime, dashboard)`` runs once the rig is
    powered, before ``ready`` (a workload, a probe)."""
    import viser

    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.runtime import Runtime
    from app.ui.dashboard import Dashboard

    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    runtime = Runtime(rig)
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    dashboard = (dashboard_cls or Dashboard)(server, runtime)
    runtime.start()
    dashboard.start()
    for powered in runtime.power_on():  # as `python -m app` starts it
        powered.result(10)
    if setup is not None:
        setup(rig, runtime, dashboard)

    def stop() -> None:
        dashboard.stop()
        runtime.stop()
        server.stop()
    serve_until_stdin_closes(stop)
