"""The State tab's event log (docs/dashboard.md "Event log"): every device's alarms,
emergencies and state changes, each row naming its device, and no flood while a drive moves.

Before, the dashboard gave the log the FastCAT ids only: a servo drive raising alarm 16
FOLLOWING_ERROR on a jammed load (static/scenarios/drive_jammed_load.toml) left no row.
"""

from __future__ import annotations

import html
import re
from collections.abc import Iterator

import pytest
import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.panels.event_log import MAX_ROWS

TIMEOUT_S = 60


def log_rows(dashboard: Dashboard) -> list[tuple[str, str]]:
    """(server, message) of each row of the event log, newest first."""
    assert dashboard._panels is not None
    content = str(dashboard._panels.log._html.content)
    return [(html.unescape(server), html.unescape(message)) for server, message in re.findall(
        r'<td class="fr-srv">(.*?)</td><td class="fr-ts">.*?</td><td>(.*?)</td>', content)]


@pytest.fixture(scope="module")
def jammed() -> Iterator[tuple[Dashboard, int]]:
    """The default rig, its Modbus drive moving into a jammed load; yields the dashboard and
    how many log rows the drive added in 1 s of unobstructed motion."""
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    runtime.set_paused(True)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    dashboard = Dashboard(server, runtime)  # ticked by the test
    runtime.start()
    try:
        runtime.advance(1_000_000).result(timeout=TIMEOUT_S)
        runtime.command("drive", "enable", {"on": True}).result(timeout=TIMEOUT_S)
        # As static/scenarios/drive_jammed_load.toml: a profile velocity, then a long move.
        runtime.command("drive", "write_register", {"register": 12, "value": 6000}).result(
            timeout=TIMEOUT_S)
        runtime.advance(100_000).result(timeout=TIMEOUT_S)
        dashboard.tick()
        before = sum(1 for server_id, _ in log_rows(dashboard) if server_id == "drive")
        runtime.command("drive", "move", {"position": 24000}).result(timeout=TIMEOUT_S)
        for _ in range(10):  # 1 s of motion, ticked as the thread would
            runtime.advance(100_000).result(timeout=TIMEOUT_S)
            dashboard.tick()
        moving = sum(1 for server_id, _ in log_rows(dashboard) if server_id == "drive") - before
        runtime.command("drive", "jam_load", {"active": True}).result(timeout=TIMEOUT_S)
        runtime.advance(1_000_000).result(timeout=TIMEOUT_S)
        dashboard.tick()
        yield dashboard, moving
    finally:
        runtime.stop()
        server.stop()


def test_drive_alarm_is_in_the_log_with_the_drive_named(
        jammed: tuple[Dashboard, int]) -> None:
    dashboard, _ = jammed
    rows = log_rows(dashboard)
    assert ("drive", "alarm 16 FOLLOWING_ERROR raised") in rows, rows
    # The drive's CiA 402 state machine is named as such, not as an EtherCAT ESM.
    assert ("drive", "CiA 402: Operation enabled -> Fault reaction active") in rows, rows


def test_motion_does_not_flood_the_log(jammed: tuple[Dashboard, int]) -> None:
    dashboard, moving = jammed
    assert moving == 0  # a drive in motion emits no alarm, emergency or state change
    assert len(log_rows(dashboard)) <= MAX_ROWS
