"""An incomplete RTU frame on the drive's line (seed 004 ch.2 "RTU transmission mode").

"Se fra la trasmissione di due byte trascorre un intervallo temporale superiore a 1,5
caratteri, il messaggio viene dichiarato incompleto e viene scartato dal ricevitore: non viene
generata dunque nessuna risposta per il master." A master whose request was cut (a noise burst,
a cable pulled mid-frame) times out and sends it again ("può essere eseguita una
ritrasmissione"): the drive must answer that retransmission. RTU framing over TCP has no
character clock; a pause of :data:`app.modbus.server.RTU_SILENCE_S` with part of a frame in the
buffer stands for the silence (docs/modbus.md "Node numbers and the line").
"""

from __future__ import annotations

import contextlib
import socket
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from modbus_line import REPLY_S, h, modbus_server, receive, rtu_adu, serve
from sim_helpers import FakeDrive, SimThread

from app.modbus.server import RTU_SILENCE_S

PAUSE_S = 3 * RTU_SILENCE_S  # a master's pause: well past the silence
QUIET_S = 0.3  # how long a test waits to call "no reply" silence


def rtu(unit: int, pdu: str) -> bytes:
    return rtu_adu(unit, h(pdu))


READ_D3 = rtu(5, "03 0003 0001")
D3_IS_50 = rtu(5, "03 02 0032")


@pytest.fixture(params=["rtu", "rtu+call"], ids=["submit", "call"])
def port(request: pytest.FixtureRequest) -> Iterator[int]:
    """An RTU-over-TCP line with a drive at node 5, served as ``python -m app`` does (``call``)
    or through the simulation thread's queue (``submit``)."""
    with serve([FakeDrive.default(node_id=5)], request.param) as line:
        yield line.port


def connect(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=REPLY_S)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # each write its own segment
    return sock


@pytest.mark.parametrize("cut", [1, 2, 4, 6], ids=lambda n: f"{n}-bytes")
def test_the_retransmission_after_an_incomplete_frame_is_answered(port: int, cut: int) -> None:
    """The first ``cut`` bytes of a request, a pause, then the master sends it again in full."""
    with connect(port) as sock:
        sock.sendall(rtu(5, "06 0003 000A")[:cut])
        assert receive(sock, QUIET_S) == b""
        time.sleep(PAUSE_S)
        sock.sendall(READ_D3)
        assert receive(sock, REPLY_S) == D3_IS_50


def test_a_frame_split_by_a_silence_is_incomplete_and_gets_no_reply(port: int) -> None:
    """Both halves are discarded (the second alone is garbage); nothing is written."""
    write = rtu(5, "06 0003 000A")
    with connect(port) as sock:
        sock.sendall(write[:3])
        time.sleep(PAUSE_S)
        sock.sendall(write[3:])
        assert receive(sock, QUIET_S) == b""
        time.sleep(PAUSE_S)
        sock.sendall(READ_D3)
        assert receive(sock, REPLY_S) == D3_IS_50


def test_a_frame_in_pieces_without_a_silence_is_one_frame(port: int) -> None:
    """TCP may cut a frame into segments: pieces that follow at once are still one frame."""
    with connect(port) as sock:
        for i in range(0, len(READ_D3), 2):
            sock.sendall(READ_D3[i:i + 2])
        assert receive(sock, REPLY_S) == D3_IS_50


def test_a_request_read_with_a_frame_of_bad_crc_before_it_is_answered(port: int) -> None:
    """ch.2: a frame with a wrong CRC is discarded without a reply; the request the same read
    brought behind it is a frame of its own (pymodbus's RTU framer dropped the whole read)."""
    bad = rtu(5, "06 0003 000A")[:-1] + b"\x00"
    with connect(port) as sock:
        sock.sendall(bad + READ_D3)
        assert receive(sock, REPLY_S) == D3_IS_50


STALL_S = 3 * RTU_SILENCE_S  # one connection's request held up this long in the rig
PREMISE_TRIES = 5  # tries at a gap within the silence on a loaded machine


@contextlib.contextmanager
def stalled_line() -> Iterator[int]:
    """The ``call`` path (``python -m app``), its first rig call held up for STALL_S, as a
    busy rig holds it: the server's one event loop is blocked meanwhile."""
    drives = [FakeDrive.default(node_id=5)]
    stalled: list[bool] = []
    with SimThread(drives) as sim:
        def call(fn: Callable[[], Any]) -> Any:
            if not stalled:
                stalled.append(True)
                time.sleep(STALL_S)
            return sim.call(fn)

        with modbus_server(drives, sim, "rtu", call) as server:
            yield server.port


def test_a_stall_on_one_connection_does_not_cut_another_connection_s_frame() -> None:
    """While connection A's rig call blocks the loop past the silence, connection B's bytes
    wait unread in the socket. B's frame came in two pieces 30 ms apart, no silence on B's
    line; measured when the loop read the second piece, the gap was the stall's, and B's
    first piece was dropped as cut (no reply).

    The test's own sleeps are wall time: on a loaded machine one of 50 ms lasted 280 ms, and
    B's pieces then came farther apart than the silence, which the server rightly cuts. Such
    a try proves nothing either way and is made again; the reply is checked on every try
    whose pieces came within the silence."""
    for _ in range(PREMISE_TRIES):
        with stalled_line() as port, connect(port) as a, connect(port) as b:
            b.sendall(READ_D3[:3])
            first_s = time.monotonic()
            time.sleep(0.05)  # read by the loop before A's request comes
            a.sendall(READ_D3)
            time.sleep(0.03)  # the loop is now blocked in A's call
            gap_s = time.monotonic() - first_s
            b.sendall(READ_D3[3:])
            assert receive(a, REPLY_S) == D3_IS_50
            answer = receive(b, REPLY_S)
        if gap_s < RTU_SILENCE_S:
            assert answer == D3_IS_50
            return
    pytest.fail(f"B's pieces came {gap_s * 1000:.0f} ms apart or more on every try")


def test_a_silence_after_a_stall_still_cuts_the_frame() -> None:
    """B's line silent from before the stall to well after it: the piece is dropped, the
    rest alone is garbage (no reply), the retransmission is answered. Only bytes read right
    after the stall count from its start."""
    write = rtu(5, "06 0003 000A")
    with stalled_line() as port, connect(port) as a, connect(port) as b:
        b.sendall(write[:3])
        time.sleep(0.05)
        a.sendall(READ_D3)
        assert receive(a, REPLY_S) == D3_IS_50  # the stall is over
        time.sleep(PAUSE_S)
        b.sendall(write[3:])
        assert receive(b, QUIET_S) == b""
        time.sleep(PAUSE_S)
        b.sendall(READ_D3)
        assert receive(b, REPLY_S) == D3_IS_50
