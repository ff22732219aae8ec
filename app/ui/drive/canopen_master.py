"""The frames the dashboard's small CANopen master sends: NMT, SDO upload / download.

DS 301 layouts (seed 004 ch. 4 "Stati e Cambiamento di stato", "Device Configuration via
SDOs"): NMT on COB-ID 0 with (command, node-ID); SDO requests on 0x600 + node-ID, 8 bytes,
index little-endian, expedited with the size indicated. Pure functions; the panel hands the
frames to the drive's CANopen node in the simulation thread.
"""

from __future__ import annotations

from dataclasses import dataclass

NMT_COB_ID = 0x000
SDO_REQUEST_BASE = 0x600

# NMT command specifiers (DS 301; the seed's table of NMT services).
NMT_COMMANDS: dict[str, int] = {
    "Start (0x01)": 0x01,
    "Stop (0x02)": 0x02,
    "Enter pre-operational (0x80)": 0x80,
    "Reset node (0x81)": 0x81,
    "Reset communication (0x82)": 0x82,
}

# CiA 402 controlword commands (ch. 4 worked sequence: 0x06, 0x07, 0x0F; 0x80 resets a fault).
CONTROLWORD_COMMANDS: dict[str, int] = {
    "Shutdown": 0x0006,
    "Switch on": 0x0007,
    "Enable op.": 0x000F,
    "Disable": 0x0000,
    "Quick stop": 0x0002,
    "Fault reset": 0x0080,
}
CONTROLWORD = (0x6040, 0)
HEARTBEAT = (0x1017, 0)

# Expedited download command byte by data size (n = 4 - size in bits 2-3, e and s set).
_DOWNLOAD_CMD = {1: 0x2F, 2: 0x2B, 3: 0x27, 4: 0x23}
UPLOAD_CMD = 0x40


@dataclass(frozen=True)
class Frame:
    can_id: int
    data: bytes


def nmt(command: int, node_id: int) -> Frame:
    """An NMT command for one node (node-ID 0 addresses every node)."""
    return Frame(NMT_COB_ID, bytes((command & 0xFF, node_id & 0x7F)))


def sdo_download(node_id: int, index: int, sub: int, value: int, size: int) -> Frame:
    """An expedited download of ``value`` in ``size`` bytes (1..4, two's complement)."""
    if size not in _DOWNLOAD_CMD:
        raise ValueError(f"an expedited SDO carries 1..4 bytes, not {size}")
    raw = (value % (1 << (8 * size))).to_bytes(size, "little")
    payload = bytes((_DOWNLOAD_CMD[size],)) + index.to_bytes(2, "little") + bytes((sub,)) + raw
    return Frame(SDO_REQUEST_BASE + node_id, payload.ljust(8, b"\x00"))


def sdo_upload(node_id: int, index: int, sub: int) -> Frame:
    payload = bytes((UPLOAD_CMD,)) + index.to_bytes(2, "little") + bytes((sub,))
    return Frame(SDO_REQUEST_BASE + node_id, payload.ljust(8, b"\x00"))


def parse_object(text: str) -> tuple[int, int]:
    """``0x6041:0`` / ``6041`` / ``0x1018:1`` -> (index, sub); hex index, decimal sub."""
    head, _, sub = text.strip().partition(":")
    index = int(head, 16)
    sub_no = int(sub, 0) if sub.strip() else 0
    if not (0 <= index <= 0xFFFF and 0 <= sub_no <= 0xFF):
        raise ValueError(f"{text!r} is not an object address (0x0000:0 .. 0xFFFF:255)")
    return index, sub_no


def parse_int(text: str) -> int:
    """A decimal, 0x hex or negative value."""
    return int(text.strip(), 0)
