"""The drive's front in the 3D axis shows the network LEDs of its fieldbus only.

Seed 004 prints LEDs for one side of the drive: ch. 5 "Connessioni e Leds Drive EtherCAT"
(L/A, Status, L/A, Error over the two RJ45 of the EtherCAT drive). Chapters 2 (Modbus RTU),
4 (CANopen) and 6 (Profinet) print none. A Modbus or CANopen drive drew the four EtherCAT
LEDs all dark, which a trainee reads as "the drive's network is dead".
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
import viser
from served_dashboard import local_server

from app.ui.drive.axis_scene import AxisScene
from devices.servo.leds import BUS_LEDS, NETWORK_LEDS

AXIS = {"neg_limit": -60000.0, "pos_limit": 660000.0, "home_switch": -3000.0,
        "carriage": 0.0, "motor_turns": 0.0}


@pytest.fixture(scope="module")
def server() -> Iterator[viser.ViserServer]:
    with local_server() as server:
        yield server


def snap(fieldbus: str) -> dict[str, Any]:
    return {"powered": True, "display": "Fr", "fieldbus": fieldbus, "node_id": 1,
            "position_counts": 0, "velocity": 0.0, "limits": {}, "axis": AXIS,
            "leds": dict.fromkeys(NETWORK_LEDS, "off")}


@pytest.mark.parametrize(("fieldbus", "shown"), [
    ("modbus", []), ("canopen", []), ("profinet", []), ("ethercat", list(NETWORK_LEDS))])
def test_only_the_bus_leds_are_drawn(server: viser.ViserServer, fieldbus: str,
                                     shown: list[str]) -> None:
    scene = AxisScene(server, f"probe_{fieldbus}", -6.0, 12.0)
    scene.update("drive", snap(fieldbus), 0)
    assert scene.network_leds_shown() == shown
    texts = [str(label.text) for label in scene.labels() if label.visible]
    assert [t for t in texts if t.startswith(NETWORK_LEDS)] == [f"{n} off" for n in shown]


def test_leds_follow_the_fieldbus_latched_at_power_up(server: viser.ViserServer) -> None:
    """c9 is read at power-up (seed 004 ch. 2, 4, 5): a drive set to EtherCAT and powered
    again gets its LEDs, and loses them back on Modbus."""
    scene = AxisScene(server, "probe_switch", -6.0, 12.0)
    scene.update("drive", snap("modbus"), 0)
    scene.update("drive", snap("ethercat"), 1000)
    assert scene.network_leds_shown() == list(NETWORK_LEDS)
    scene.update("drive", snap("modbus"), 2000)
    assert scene.network_leds_shown() == []


def test_the_table_names_the_ethercat_leds_only() -> None:
    assert BUS_LEDS == {"ethercat": NETWORK_LEDS}
