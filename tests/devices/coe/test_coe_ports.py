"""The drive's two EtherCAT ports and their L/A LEDs (seed 004 ch. 5 "Connessioni e Leds Drive
EtherCAT": "L/A Status L/A Error / Ingresso RJ45 Uscita RJ45", "L/A Verde Link Active rete
ethernet"): one L/A per RJ45, IN with Status, OUT with Error. The OUT port has link only
while a next slave is cabled and powered; with link, the frames it passes on flicker it
(ETG.1300 L/A, as the TRS-CAT's LINK-ACT OUT). docs/ethercat-coe.md §LEDs. The drive ahead
of a FastCAT: tests/devices/master/test_master_port_link.py.
"""

from __future__ import annotations

from typing import Any

from coe_bench import make_bench

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from devices.ethercat import AlState


def _leds(rig: Any, drive: str = "drive_ec") -> dict[str, str]:
    return rig.snapshot()["devices"][drive]["leds"]


def test_a_drive_alone_has_link_and_traffic_on_its_in_port_only() -> None:
    bench = make_bench()
    bench.go(AlState.PREOP)
    bench.run(5)
    assert bench.slave.leds.snapshot() == {
        "L/A IN": "flickering", "Status": "blinking", "L/A OUT": "off", "Error": "off"}


def test_the_last_drive_on_the_default_line_has_no_out_link() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.advance(4000)
    assert rig.snapshot()["devices"]["drive_ec-ecat"]["esm"] == "OP"
    assert (_leds(rig)["L/A IN"], _leds(rig)["L/A OUT"]) == ("flickering", "off")
