"""The Drive tab's title names how a master reaches the drive: the Modbus or CANopen node
(parameter c7), and for the drive on the EtherCAT line its station address. Seed 004 ch. 5
"Parametrizzazione EtherCAT per drive" (l. 4381-4383): "Non è necessario impostare il nodo del
drive (parametro C7), in quanto è lo stesso ethercat che definisce l'indirizzamento del drive";
the title read "EtherCAT node 3" (the rig file's c7) next to a line that shows it as 1004.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
import viser

from app.modbus.line import ServedLine
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.drive.drive_state import title
from app.ui.drive.view import bus_companions


def _titles(tmp_path: Path) -> dict[str, str]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path)
    rig.run_until(5_000_000)  # the line in OP: the master has set the station addresses
    snapshot = rig.snapshot()
    devices = snapshot["devices"]
    out = {}
    for drive in ("drive", "drive_co", "drive_ec"):
        _node, slave = (devices.get(i) if i else None for i in bus_companions(snapshot, drive))
        out[drive] = title(drive, devices[drive], 0, slave)
    return out


def test_modbus_and_canopen_drives_name_their_c7_node(tmp_path: Path) -> None:
    titles = _titles(tmp_path)
    assert "Modbus RTU node 1 ·" in titles["drive"]
    assert "CANopen node 2 ·" in titles["drive_co"]


def test_the_ethercat_drive_names_its_station_address_not_c7(tmp_path: Path) -> None:
    text = _titles(tmp_path)["drive_ec"]
    assert "EtherCAT station 1004 ·" in text
    assert "node" not in text


def test_a_modbus_drive_names_the_line_the_rig_serves(tmp_path: Path) -> None:
    """The title said "Modbus RTU node 1" (the drive's c9, seed 004 ch. 2) next to a server
    that speaks Modbus TCP (MBAP) on its port: a trainee reached for an RTU adapter. It says
    both: the drive's bus and node, and the framing and port the rig really serves it on
    (the runtime's ``modbus``, set when the server listens; docs/modbus.md)."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path)
    devices = rig.snapshot()["devices"]
    tcp, rtu = ServedLine("socket", 5020), ServedLine("rtu", 5023)
    assert "Modbus RTU node 1 · served as Modbus TCP on :5020 ·" in title(
        "drive", devices["drive"], 0, None, tcp)
    assert "Modbus RTU node 1 · served as Modbus RTU over TCP on :5023 ·" in title(
        "drive", devices["drive"], 0, None, rtu)
    assert "served" not in title("drive_co", devices["drive_co"], 0, None, tcp)  # CANopen
    assert "served" not in title("drive", devices["drive"], 0)  # no server: nothing to say


@pytest.mark.parametrize("framer", ["socket", "rtu"])
def test_the_runtime_keeps_the_framing_and_port_the_server_listens_on(framer: str) -> None:
    from app.cli import _start_modbus
    from app.runtime import Runtime

    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    assert runtime.modbus is None
    args = argparse.Namespace(host="127.0.0.1", modbus_framer=framer)
    server = _start_modbus(runtime, args, 0)  # port 0: any free one, the real one is kept
    try:
        assert server.port != 0
        assert runtime.modbus == ServedLine(framer, server.port)
    finally:
        server.stop_in_thread()


def test_the_drive_tab_shows_the_runtimes_line() -> None:
    """The Drive tab reads ``runtime.modbus`` at each frame: the server starts after the
    dashboard was built (app/cli.py). The default rig has three drives, so each page gets its
    pick's title (per page): the title the panel makes for the default pick is read here."""
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        drives = Dashboard(server, runtime).drives
        assert drives is not None
        shown: list[str] = []
        drives.state._title.show = (  # type: ignore[method-assign]
            lambda content_of, pick_of: shown.append(content_of(pick_of(None))))
        drives.update(runtime.frame)
        runtime.modbus = ServedLine("rtu", 5999)
        drives.update(runtime.frame)
        assert "served" not in shown[0]
        assert "<b>drive</b> · Modbus RTU node 1 · served as Modbus RTU over TCP on :5999 ·" \
            in shown[1]
    finally:
        server.stop()
