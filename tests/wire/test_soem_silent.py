"""SOEM on a line whose first slave is a drive that does not answer (c9 = 3 at power-up, seed
004 ch. 2): its ESC passes the frames on, so the master finds the FastCAT behind it, as the
built-in master does (docs/ethercat-wire.md "Silent slaves"). Until session 16 the wire cut
the line at the silent drive and SOEM found no slave. SOEM's frames cross the drive's ESC, so
its L/A flicker (docs/ethercat-coe.md "LEDs of a drive with c9 != 11"; until session 20 they
stayed on). Skipped as test_soem_line.py is."""

from __future__ import annotations

import time

from test_soem_line import (
    DEADLINE_S,
    PERIOD_S,
    Master,
    favoured,
    model_call,
    powered_runtime,
    until,
)
from test_wire_silent import SILENT_DRIVE_FIRST
from wire_line import veth_pair

from app.ethercat_wire.bridge import start_wire
from app.rig_config import build_rig, parse_rig_spec


def test_soem_finds_the_slave_behind_a_silent_drive():
    with veth_pair("q") as (master_if, slave_if), favoured():
        runtime = powered_runtime(build_rig(parse_rig_spec(SILENT_DRIVE_FIRST)))
        bridge = start_wire(runtime, slave_if)
        master = Master(master_if)
        try:
            n, found = master("init")
            assert n == 1
            assert found[0][0] == "FastCAT"
            drive = runtime.rig.devices["drive_ec"]
            master("map", [])
            # no frame for longer than the 50 ms activity window, in A's simulated time
            until(lambda: model_call(runtime, lambda: drive.snapshot()["leds"]["L/A IN"]) ==
                  "on", "the drive's L/A IN on (link, no traffic)")
            leds: dict[str, str] = {}
            deadline = time.monotonic() + DEADLINE_S
            while leds.get("L/A IN") != "flickering":  # process data, 1 s at a time
                assert time.monotonic() < deadline, leds
                master.conn.send(("cycles", 250, PERIOD_S, {}))
                while not master.conn.poll(0.02) and leds.get("L/A IN") != "flickering":
                    leds = model_call(runtime, lambda: drive.snapshot()["leds"])
                assert master.conn.poll(30) and master.conn.recv()[0] == "ok"
            assert leds == {"L/A IN": "flickering", "Status": "off", "L/A OUT": "flickering",
                            "Error": "off"}
        finally:
            master.close()
            bridge.stop()
            runtime.stop()
