"""The default rig served with its dashboard in-process (app.screenshots.ServedRig), and a
wait for the dashboard thread to draw the current frame. Shared by the tests that read the
dashboard's widgets after a model change (test_canopen_master_panel, test_reset_fault_control).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import ServedRig


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
