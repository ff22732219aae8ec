"""The Drive tab's title names how a master reaches the drive: the Modbus or CANopen node
(parameter c7), and for the drive on the EtherCAT line its station address. Seed 004 ch. 5
"Parametrizzazione EtherCAT per drive" (l. 4381-4383): "Non è necessario impostare il nodo del
drive (parametro C7), in quanto è lo stesso ethercat che definisce l'indirizzamento del drive";
the title read "EtherCAT node 3" (the rig file's c7) next to a line that shows it as 1004.
"""

from __future__ import annotations

from pathlib import Path

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
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
