"""A drive in alarm shows it on the 3D line, as its own front does.

Seed 004 ch. 5 "Codici allarmi specifici": "Gli allarmi vengono visualizzati sia sul display
del drive, sia sul pc" (l. 4830), numbered as the table there (34 "Timeout sincronizzazione
con il Master ECAT"); the drive's two-digit display shows the number (devices/servo/display.py).
The line draws the EtherCAT drive without its axis (docs/dashboard.md "The EtherCAT line"), so
its body carries the number: "alarm 34" under its ESM state. Before, a drive back in OP with
alarm 34 latched read "ESM OP" and nothing else: a trainee watching the line could not tell.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import pytest
from served_dashboard import local_server

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.ui.dashboard import Dashboard
from app.ui.line.bodies import SlaveBody

BOOT_US = 8_000_000  # the FastCAT's scan and every slave INIT -> OP
DRIVE_CABLE = 3  # cpx -> drive_ec-ecat on the default line


@dataclass
class Line:
    rig: Rig
    dashboard: Dashboard

    @property
    def body(self) -> SlaveBody:
        assert self.dashboard.line is not None
        body = self.dashboard.line.scene.bodies["drive_ec-ecat"]
        assert isinstance(body, SlaveBody)
        return body

    def draw(self) -> None:
        assert self.dashboard.line is not None
        self.dashboard.line.scene.update(self.rig.snapshot(), self.rig.clock.now_us)


@pytest.fixture
def line() -> Iterator[Line]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.run_until(BOOT_US)
    with local_server() as server:
        dashboard = Dashboard(server, Runtime(rig))
        dashboard.tick()
        yield Line(rig, dashboard)


def _sync_timeout(line: Line) -> None:
    """No frame for the SM watchdog time in OP: alarm 34, the drive back in OP once the
    cable is plugged again (the alarm stays latched until a reset)."""
    rig = line.rig
    rig.apply("master", "pull_cable", {"cable": DRIVE_CABLE})
    rig.run_until(rig.clock.now_us + 300_000)
    rig.apply("master", "plug_cable", {"cable": DRIVE_CABLE})
    rig.run_until(rig.clock.now_us + 4_000_000)


def test_alarm_34_shows_on_the_drive_s_body(line: Line) -> None:
    _sync_timeout(line)
    snap = line.rig.snapshot()["devices"]
    assert snap["drive_ec"]["alarms"] == [34]
    assert snap["drive_ec"]["display"] == "34"
    line.draw()
    assert line.body.paint.text("esm") == "ESM\nOP"
    assert line.body.paint.text("alarm") == "alarm 34"
    assert line.body.paint.labels["alarm"].visible


def test_the_alarm_goes_with_its_reset(line: Line) -> None:
    _sync_timeout(line)
    rig = line.rig
    rig.apply("drive_ec-ecat", "write_object", {"index": 0x6040, "sub": 0, "value": 0x80})
    rig.run_until(rig.clock.now_us + 10_000)
    assert rig.snapshot()["devices"]["drive_ec"]["alarms"] == []
    line.draw()
    assert "alarm" in line.body.paint.labels and line.body.paint.text("alarm") == ""
    assert not line.body.paint.labels["alarm"].visible


def test_a_drive_without_alarm_shows_none(line: Line) -> None:
    line.draw()
    assert "alarm" in line.body.paint.labels and line.body.paint.text("alarm") == ""
    assert not line.body.paint.labels["alarm"].visible
