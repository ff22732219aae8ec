"""Who drives the line gives the slaves their station address (ESC 0x0010, ETG.1000.4): the
FastCAT's address check (seed 000 §6.19) compares the one the master that drives it assigned.
In external mode (a master on the wire) that is what the wire master wrote, 0 (the ESC's
power-on value) until it writes; handed back, the built-in master's own ``master_address``."""

from __future__ import annotations

from pathlib import Path

from app.rig_config import build_rig, load_rig_spec

DEFAULT_RIG = Path(__file__).resolve().parents[3] / "static" / "rigs" / "default.toml"


def test_the_master_that_drives_the_line_gives_the_fastcat_its_address() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    master, fastcat = rig.devices["master"], rig.devices["fastcat"]
    assert fastcat.logical_address() == fastcat.master_address == 1  # the rig file's
    master.set_external(True)
    assert fastcat.logical_address() == 0  # the ESC's 0x0010 before the wire master writes
    master.external_station_address(0, 7)
    assert fastcat.logical_address() == 7
    # the master's own view keeps the built-in master's name for the slave (its log lines)
    assert rig.snapshot()["devices"]["master"]["slaves"][0]["station_address"] == 1001
    master.set_external(False)
    assert fastcat.logical_address() == 1
