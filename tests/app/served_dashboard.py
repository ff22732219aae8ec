"""The default rig served with its dashboard in-process (app.screenshots.ServedRig), and a
wait for the dashboard thread to draw the current frame. Shared by the tests that read the
dashboard's widgets after a model change (test_canopen_master_panel, test_reset_fault_control).

Also the default rig's dashboard with no runtime thread, ticked by the test (the focus, label
and caption tests), and a bare viser server on a free port for the scene and panel tests.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import ServedRig, free_port
from app.ui.dashboard import Dashboard


@contextlib.contextmanager
def served_default_rig(boot_s: float) -> Iterator[ServedRig]:
    """The default rig served and stepped ``boot_s`` simulated seconds; stopped after."""
    live = ServedRig.start(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    try:
        live.advance(boot_s)
        yield live
    finally:
        live.stop()


def drawn(live: ServedRig) -> None:
    """One more frame, drawn by the dashboard thread: waited for on the dashboard's own
    count, not on a number of simulation round trips (a loaded machine's tick outlasted
    200 of them; tests/app/test_served_dashboard_drawn.py)."""
    live.advance(0.05)
    live.drawn()


@contextlib.contextmanager
def local_server() -> Iterator[viser.ViserServer]:
    """A viser server on a free port of 127.0.0.1; stopped after."""
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        yield server
    finally:
        server.stop()


@contextlib.contextmanager
def ticked_dashboard(boot_steps: int = 0) -> Iterator[Dashboard]:
    """The default rig stepped ``boot_steps`` times by hand, then its dashboard on a server of
    its own with the first frame drawn. The runtime is never started: the test ticks."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(boot_steps):
        rig.step()
    with local_server() as server:
        dashboard = Dashboard(server, Runtime(rig))
        dashboard.tick()
        yield dashboard
