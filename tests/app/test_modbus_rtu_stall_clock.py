"""The RTU silence across a loop stall (app/modbus/server.py LoopStalls), on a clock the test
sets. Seed 004 ch.2: a frame is cut only by a silence of more than 1.5 characters between two
bytes (RTU_SILENCE_S over TCP). Bytes read right after a stall may have come at any time
during it, so the gap before them is measured from the stall's start; the gap after them must
be measured from when they were read (the latest they can have come), or a frame whose next
piece came well within the silence is dropped as cut."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest
from own_loop import run
from pymodbus.framer import FramerRTU

from app.modbus import server as modbus_server
from app.modbus.server import FRAMERS, LoopStalls, _DriveTcpServer


def _rtu(unit: int, pdu: str) -> bytes:
    body = bytes((unit,)) + bytes.fromhex(pdu)
    return body + FramerRTU.compute_CRC(body).to_bytes(2, "big")


def test_a_piece_read_after_a_short_stall_does_not_start_a_silence(
        monkeypatch: pytest.MonkeyPatch) -> None:
    now = [0.0]
    monkeypatch.setattr(modbus_server, "time", SimpleNamespace(monotonic=lambda: now[0]))
    frame = _rtu(5, "03 0003 0001")
    answered: list[Any] = []

    async def line() -> None:
        stalls = LoopStalls()
        server = _DriveTcpServer(("127.0.0.1", 0), FRAMERS["rtu"],
                                 lambda _h, request, _a: answered.append(request), stalls)
        handler = server.callback_new_connection()
        handler.datagram_received(frame[:3], None)  # read at 0 s
        now[0] = 0.010
        stalls.begin()  # another connection's rig call blocks the loop for 80 ms
        now[0] = 0.090
        stalls.end()
        handler.datagram_received(frame[3:5], None)  # came during the stall, read at its end
        now[0] = 0.140  # 50 ms after that read: no silence on this line
        handler.datagram_received(frame[5:], None)

    run(line())
    assert [r.frame for r in answered] == [frame[1:-2]]
