"""The bus monitor of the drive panel: every frame the node saw or sent, decoded.

Only for views; the node records, :mod:`devices.canopen.decode` names. Frames are kept in a
ring (the last :data:`FRAME_LOG`), with the last SDO and PDO exchange kept apart so a view can
show them even when cyclic PDOs have scrolled them away.

A heartbeat that repeats the last one of its COB-ID (same state) is no row of the ring: it is
counted on that COB-ID's heartbeat line (:meth:`BusMonitor.heartbeats`: state, count, last
time, period), as a CAN analyser's receive list shows a periodic frame once with its count and
cycle time. Otherwise one node's heartbeats (every 0x1017 ms) pushed a trainee's SDO exchange
out of the view's last rows within seconds. The boot-up and a heartbeat with a new state stay
rows: they are events. Node guarding answers toggle bit 7 each time, so they stay rows.
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
        self._beats: dict[str, dict[str, Any]] = {}  # heartbeat lines by COB-ID

    def record(self, frame: CanFrame, ctx: Context) -> None:
        kind, text = describe(frame.can_id, frame.data, frame.rtr, ctx)
        direction = "rx" if frame.rx else "tx"
        self.counts[direction] += 1
        row = {"t": frame.t_us / 1e6, "dir": direction, "id": f"0x{frame.can_id:03X}",
               "dlc": frame.length, "data": "R" if frame.rtr else fmt_bytes(frame.data),
               "kind": kind, "text": text}
        beat = kind == "NMT-EC" and not frame.rtr and len(frame.data) == 1 and frame.data[0]
        if beat and self._beat(row):
            return
        self.frames.append(row)
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

    def _beat(self, row: dict[str, Any]) -> bool:
        """Count a heartbeat (or a guarding answer) on its line; True when it repeats the
        last one of its COB-ID and direction, so it is no row."""
        key = f"{row['id']} {row['dir']}"
        beat = self._beats.get(key)
        if beat is None or beat["data"] != row["data"]:
            self._beats[key] = {**row, "count": 1, "period": None}
            return False
        beat["period"] = round(row["t"] - beat["t"], 6)
        beat.update(t=row["t"], count=beat["count"] + 1)
        return True

    def recent(self, count: int) -> list[dict[str, Any]]:
        return list(self.frames)[-count:]

    def heartbeats(self) -> list[dict[str, Any]]:
        """One line per heartbeat COB-ID and direction: the last state's row (``t`` its last
        time), ``count`` in a row with that state, ``period`` (s) between the last two."""
        return [dict(b) for b in self._beats.values()]


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
