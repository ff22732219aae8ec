"""A powered slave that does not answer (a drive whose c9 did not select EtherCAT at power-up,
seed 004 ch. 2) passes the frames on (its ESC forwards them whatever its application does):
the frames' physical path, not the chain of answers, decides which cables they cross
(docs/ethercat-master.md "Damaged cable")."""

from __future__ import annotations

from line_bench import US, master_view
from test_master_port_link import _drive_first


def test_a_damaged_cable_behind_a_silent_first_slave_spoils_frames() -> None:
    """Cable 1 (drive -> FastCAT) damaged: the frames still cross it (the silent drive at
    position 0 forwards them), so the master loses frames and the ESCs count."""
    rig = _drive_first(c9=3)
    rig.run_until(4 * US)
    master = rig.devices["master"]
    before = master.lost_frames
    rig.apply("master", "damage_cable", {"cable": 1, "percent": 100})
    rig.run_until(4 * US + 50_000)
    assert master.lost_frames - before >= 40
    esc = [s["esc_errors"] for s in master_view(rig)["slaves"]]
    assert esc[1]["invalid"][0] > 0  # the FastCAT's IN port: the first to see it spoiled
    assert esc[0]["forwarded"][1] > 0  # the drive's ESC forwards it back, marked
