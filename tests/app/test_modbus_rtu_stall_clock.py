"""The RTU silence across a loop stall (app/modbus/server.py LoopStalls), on a clock the test
sets. Seed 004 ch.2: a frame is cut only by a silence of more than 1.5 characters between two
bytes (RTU_SILENCE_S over TCP). Bytes read right after a stall may have come at any time
during it, so the gap before them is measured from the stall's start; the gap after them must
be measured from when they were read (the latest they can have come), or a frame whose next
piece came well within the silence is dropped as cut."""

from __future__ import annotations

import asyncio
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


FRAME = _rtu(5, "03 0003 0001")


@pytest.fixture
def now(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """The server's monotonic clock, which the test moves by hand."""
    clock = [0.0]
    monkeypatch.setattr(modbus_server, "time", SimpleNamespace(monotonic=lambda: clock[0]))
    return clock


def _connection(answered: list[Any]) -> tuple[LoopStalls, Any]:
    """One RTU-over-TCP connection of a server whose requests land in ``answered``, and the
    loop's stall record it shares with the other connections."""
    stalls = LoopStalls()
    server = _DriveTcpServer(("127.0.0.1", 0), FRAMERS["rtu"],
                             lambda _h, request, _a: answered.append(request), stalls)
    return stalls, server.callback_new_connection()


def test_a_piece_read_after_a_short_stall_does_not_start_a_silence(
        now: list[float]) -> None:
    answered: list[Any] = []

    async def line() -> None:
        stalls, handler = _connection(answered)
        handler.datagram_received(FRAME[:3], None)  # read at 0 s
        now[0] = 0.010
        stalls.begin()  # another connection's rig call blocks the loop for 80 ms
        now[0] = 0.090
        stalls.end()
        handler.datagram_received(FRAME[3:5], None)  # came during the stall, read at its end
        now[0] = 0.140  # 50 ms after that read: no silence on this line
        handler.datagram_received(FRAME[5:], None)

    run(line())
    assert [r.frame for r in answered] == [FRAME[1:-2]]


def test_a_piece_read_late_in_the_loop_s_first_pass_after_a_stall_came_during_it(
        now: list[float]) -> None:
    """On a loaded machine the loop can read the bytes that waited through a stall well after
    the stall's end (the rig call's reply sent first, the thread descheduled): they were still
    read before the loop polled the sockets again, so they can have come during the stall.
    Judged by a wall-time slack after the stall, they were stamped at their read and the
    frame's first piece was dropped as cut (test_a_stall_on_one_connection... under load)."""
    answered: list[Any] = []

    async def line() -> None:
        stalls, handler = _connection(answered)
        handler.datagram_received(FRAME[:3], None)  # read at 0 s
        now[0] = 0.050
        stalls.begin()  # another connection's rig call blocks the loop for 300 ms
        now[0] = 0.350
        stalls.end()
        now[0] = 0.400  # the same loop pass, 50 ms later
        handler.datagram_received(FRAME[3:], None)

    run(line())
    assert [r.frame for r in answered] == [FRAME[1:-2]]


def test_a_piece_read_after_the_loop_polled_again_is_stamped_at_its_read(
        now: list[float]) -> None:
    """Once the loop has waited for the sockets after the stall, bytes it reads came after
    that: a piece 150 ms after the stall's end, 200 ms after the first piece, is a silence."""
    answered: list[Any] = []

    async def line() -> None:
        stalls, handler = _connection(answered)
        handler.datagram_received(FRAME[:3], None)
        now[0] = 0.010
        stalls.begin()
        now[0] = 0.050
        stalls.end()
        for _ in range(3):  # the loop goes round: it has polled the sockets since
            await asyncio.sleep(0)
        now[0] = 0.200
        handler.datagram_received(FRAME[3:], None)  # alone it is no frame: dropped too

    run(line())
    assert answered == []
