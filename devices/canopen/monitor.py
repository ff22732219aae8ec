"""The bus monitor of the drive panel: every frame the node saw or sent, decoded.

Only for views; the node records, :mod:`devices.canopen.decode` names. Frames are kept in a
ring (the last :data:`FRAME_LOG`), with the last SDO and PDO exchange kept apart so a view can
show them even when heartbeats or cyclic PDOs have scrolled them away.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from typing import Any

from devices.canopen.bus_timing import CanFrame
from devices.canopen.decode import Context, describe, sdo_parts
from devices.canopen.pdo import Pdo, split_entry
from devices.events import fmt_bytes

FRAME_LOG = 200  # frames the monitor keeps


class BusMonitor:
    def __init__(self) -> None:
        self.frames: deque[dict[str, Any]] = deque(maxlen=FRAME_LOG)
        self.last_sdo = self.last_pdo = ""
        # The last SDO exchange as plain data (decode.sdo_parts): the master's initiating
        # request and the node's latest answer to it, for a view to put in one sentence.
        self.sdo_request: dict[str, Any] | None = None
        self.sdo_response: dict[str, Any] | None = None
        self.counts = {"rx": 0, "tx": 0}

    def record(self, frame: CanFrame, ctx: Context) -> None:
        kind, text = describe(frame.can_id, frame.data, frame.rtr, ctx)
        direction = "rx" if frame.rx else "tx"
        self.counts[direction] += 1
        self.frames.append({"t": frame.t_us / 1e6, "dir": direction,
                            "id": f"0x{frame.can_id:03X}", "dlc": frame.length,
                            "data": "R" if frame.rtr else fmt_bytes(frame.data),
                            "kind": kind, "text": text})
        if kind == "SDO":
            self.last_sdo = text
            parts = sdo_parts(frame.can_id, frame.data)
            if parts is not None:
                if not parts["request"]:
                    self.sdo_response = parts
                elif parts["service"] in ("download", "upload", "abort") or \
                        self.sdo_request is None:
                    self.sdo_request, self.sdo_response = parts, None
        elif kind == "PDO":
            self.last_pdo = text

    def recent(self, count: int) -> list[dict[str, Any]]:
        return list(self.frames)[-count:]


def pdo_text(pdos: Iterable[Pdo], can_id: int, data: bytes) -> str | None:
    """"TPDO1 0x6041:00=0x637" for a frame of one of the node's PDOs in use (valid, something
    mapped), else None."""
    for pdo in pdos:
        if pdo.valid and pdo.count and pdo.can_id == can_id:
            parts, offset = [], 0
            for index, sub, bits in map(split_entry, pdo.mapped):
                chunk = data[offset:offset + bits // 8]
                offset += bits // 8
                value = f"{int.from_bytes(chunk, 'little'):#x}" if len(chunk) == bits // 8 \
                    else "?"
                parts.append(f"0x{index:04X}:{sub:02X}={value}")
            return f"{pdo.name} {' '.join(parts) or fmt_bytes(data)}"
    return None
