"""The frames a CANopen master sends a node: NMT commands, expedited SDO upload / download.

DS 301 layouts (seed 004 ch. 4 "Stati e Cambiamento di stato", "Device Configuration via
SDOs"): NMT on COB-ID 0 with (command, node-ID); SDO requests on 0x600 + node-ID, 8 bytes,
index little-endian, expedited with the size indicated. The command specifiers are the SDO
server's (devices/canopen/sdo.py), so both ends read one table. Pure functions: the dashboard's
small master builds its frames here and hands them to the node in the simulation thread.
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.canopen.nmt import NMT_COB_ID
from devices.canopen.sdo import CCS_DOWNLOAD, CCS_UPLOAD, EXPEDITED, SDO_RX_BASE, SIZE_GIVEN

EXPEDITED_SIZES = range(1, 5)


@dataclass(frozen=True)
class Frame:
    can_id: int
    data: bytes


def download_command(size: int) -> int:
    """The command byte of an expedited download of ``size`` bytes: n = 4 - size unused bytes
    in bits 2-3, e and s set (0x2F, 0x2B, 0x27, 0x23 for 1..4 bytes)."""
    if size not in EXPEDITED_SIZES:
        raise ValueError(f"an expedited SDO carries 1..4 bytes, not {size}")
    return CCS_DOWNLOAD | (4 - size) << 2 | EXPEDITED | SIZE_GIVEN


def nmt(command: int, node_id: int) -> Frame:
    """An NMT command for one node (node-ID 0 addresses every node)."""
    return Frame(NMT_COB_ID, bytes((command & 0xFF, node_id & 0x7F)))


def sdo_download(node_id: int, index: int, sub: int, value: int, size: int) -> Frame:
    """An expedited download of ``value`` in ``size`` bytes (1..4, two's complement)."""
    command = download_command(size)
    raw = (value % (1 << (8 * size))).to_bytes(size, "little")
    payload = bytes((command,)) + index.to_bytes(2, "little") + bytes((sub,)) + raw
    return Frame(SDO_RX_BASE + node_id, payload.ljust(8, b"\x00"))


def sdo_upload(node_id: int, index: int, sub: int) -> Frame:
    payload = bytes((CCS_UPLOAD,)) + index.to_bytes(2, "little") + bytes((sub,))
    return Frame(SDO_RX_BASE + node_id, payload.ljust(8, b"\x00"))
