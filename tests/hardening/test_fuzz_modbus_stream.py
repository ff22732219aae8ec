"""Modbus fuzzing through the real server on persistent connections (issue 7: >= 100,000 frames).

The fuzzed requests of fuzz_modbus.py go, framed, through ``DriveModbusServer`` as the runtime
serves it (``call``: each request served in the server's loop, between two simulation steps,
here behind a lock the test steps the drives under). Every request that reaches the PDU layer
is judged there by the oracle (modbus_oracle.py) against the line's state just before it; on
the wire, every request must reach the PDU layer in order, exactly once, and the bytes that
come back must be exactly the framed answers (reply, exception 02, or nothing), each for its
request's unit and transaction id.

- MBAP: chunks of frames pipelined on one connection; some chunks end with a broken MBAP
  header, after which the server must close the connection (every earlier frame answered).
- RTU framing over TCP: no length field, so pymodbus's RTU framer delimits a frame by its
  function code table and takes the whole buffer (docs/modbus.md): one frame at a time on one
  connection, as an RTU master does; only frames that framer can size (a fuzzed PDU it would
  read as longer or shorter is a CRC error there: covered by test_fuzz_modbus_tcp.py).

The test knows when the server is done with a write by counting the bytes its connection
handler consumed: no waiting for silences. The simulation advances between chunks (saves
finish, a reply held back by save method 1 is then sent). Sizes: 2,000 frames per framing in
CI, 100,000 with ``--full``.
"""

from __future__ import annotations

import random
import socket
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from fuzz_modbus import judge, line_state, requests
from pymodbus.framer import FramerRTU
from test_fuzz_modbus_pdu import NODES, _advance, _line
from test_fuzz_modbus_tcp import BAD_MBAP, _adu, _mbap

import app.modbus.server as server_module
from app.modbus.pdu import Outcome, Reply, Silence
from app.modbus.server import DriveModbusServer, _DriveRequestHandler, _RawDecoder

SEED = 77
REDUCED, FULL = 2_000, 100_000
CHUNK = {"socket": 200, "rtu": 1}
STEP_EVERY = 40  # frames between two simulation advances
BROKEN_EVERY = 25  # MBAP: one chunk in this many ends with a broken header
WAIT_S = 10.0


class Line:
    """The drives behind a lock; the server's view of them, recorded request by request."""

    def __init__(self) -> None:
        self.drives = _line()
        self.lock = threading.RLock()
        self.served: list[tuple[int, bytes, Outcome]] = []
        self.problems: list[str] = []
        self.consumed = 0
        self.progress = threading.Condition()

    def call(self, fn: Callable[[], Any]) -> Any:
        with self.lock:
            return fn()

    def took(self, count: int) -> None:
        with self.progress:
            self.consumed += count
            self.progress.notify_all()

    def wait_consumed(self, count: int) -> None:
        with self.progress:
            assert self.progress.wait_for(lambda: self.consumed == count, WAIT_S), \
                f"the server stopped taking frames at {self.consumed} of {count} bytes"


@contextmanager
def _served(framer: str, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Line, int]]:
    line = Line()
    real_serve, real_data = server_module.serve_line, _DriveRequestHandler.callback_data

    def serve_line(drives: Any, unit: int, pdu: bytes) -> Outcome:
        before = line_state(drives)
        outcome = real_serve(drives, unit, pdu)
        problem = judge(drives, unit, pdu, outcome, before)
        if problem:
            line.problems.append(f"#{len(line.served)} unit {unit} {pdu.hex(' ')}: {problem}")
        line.served.append((unit, pdu, outcome))
        return outcome

    def callback_data(handler: Any, data: bytes, addr: tuple | None = None) -> int:
        used = real_data(handler, data, addr)
        line.took(used)
        return used

    monkeypatch.setattr(server_module, "serve_line", serve_line)
    monkeypatch.setattr(_DriveRequestHandler, "callback_data", callback_data)
    server = DriveModbusServer(line.drives, lambda fn: None, host="127.0.0.1", port=0,
                               framer=framer, call=line.call)
    server.start_in_thread()
    try:
        yield line, server.port
    finally:
        server.stop_in_thread()


def _frames(framer: str, n: int) -> Iterator[tuple[int, bytes]]:
    """(unit, PDU) the framing can carry: non-empty; for RTU, sized by pymodbus's table."""
    rtu = FramerRTU(_RawDecoder())
    for unit, pdu in requests(random.Random(SEED), 40 * n, NODES):
        if not pdu:
            continue
        if framer == "rtu":
            adu = _adu("rtu", unit, pdu, 0)
            if rtu.decode(adu)[0] != len(adu) or rtu.decode(adu)[3] != pdu:
                continue
        yield unit, pdu


def _replies(framer: str, stream: bytes) -> tuple[list[bytes], bytes]:
    """Whole reply frames at the start of ``stream``, and the rest."""
    frames: list[bytes] = []
    while stream:
        if framer == "socket":
            size = 6 + int.from_bytes(stream[4:6], "big") if len(stream) >= 6 else 0
        elif len(stream) >= 3:
            size = 5 if stream[1] & 0x80 else 5 + stream[2] if stream[1] == 0x03 else 8
        else:
            size = 0
        if not size or len(stream) < size:
            break
        frames.append(stream[:size])
        stream = stream[size:]
    return frames, stream


class Client:
    def __init__(self, framer: str, port: int) -> None:
        self.framer, self.port = framer, port
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=WAIT_S)
        # a silent request is never acknowledged at once: Nagle would hold the next one
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.pending = b""

    def read(self, count: int) -> list[bytes]:
        """``count`` whole replies; then the connection must be quiet."""
        got: list[bytes] = []
        while len(got) < count:
            chunk = self.sock.recv(65536)
            assert chunk, f"connection closed with {count - len(got)} replies owed"
            frames, self.pending = _replies(self.framer, self.pending + chunk)
            got += frames
        assert not self.pending and len(got) == count, f"{len(got)} replies, {count} owed"
        return got

    def closed(self) -> bool:
        self.sock.settimeout(WAIT_S)
        try:
            return self.sock.recv(65536) == b""
        except ConnectionResetError:
            return True


@pytest.mark.parametrize("framer", ["socket", "rtu"])
def test_fuzz_stream_through_the_server(framer: str, full: bool,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    n = FULL if full else REDUCED
    rng = random.Random(SEED + 1)
    cases = list(_frames(framer, n))[:n]
    assert len(cases) == n
    with _served(framer, monkeypatch) as (line, port):
        client, sent = Client(framer, port), 0
        for at in range(0, n, CHUNK[framer]):
            chunk = cases[at:at + CHUNK[framer]]
            tids = [(at + i) % 0xFFFF + 1 for i in range(len(chunk))]
            frames = [_adu(framer, unit, pdu, tid)
                      for (unit, pdu), tid in zip(chunk, tids, strict=True)]
            broken = framer == "socket" and rng.randrange(BROKEN_EVERY) == 0
            if broken:
                frames.append(_mbap(1, b"\x03\x00\x01\x00\x01", 0,
                                    **BAD_MBAP[rng.choice(list(BAD_MBAP))]))
            done = len(line.served) + len(chunk)
            client.sock.sendall(b"".join(frames))
            sent += sum(map(len, frames))
            line.wait_consumed(sent)
            served = line.served[done - len(chunk):]
            assert [(u, p) for u, p, _o in served] == chunk, "frames lost before the PDU layer"
            held = [o for _u, _p, o in served if isinstance(o, Reply) and o.after_save]
            owed = {tid: _adu(framer, unit, o.pdu, tid) for (unit, _p, o), tid
                    in zip(served, tids, strict=True) if not isinstance(o, Silence)}
            if at // CHUNK[framer] % max(1, STEP_EVERY // CHUNK[framer]) == 0 or held:
                with line.lock:
                    _advance(line.drives, rng)  # saves end; a held reply goes out
            got = client.read(len(owed))
            assert sorted(got) == sorted(owed.values()), f"chunk at {at}: {got} != {owed}"
            if broken:
                assert client.closed(), "a broken MBAP header left the connection open"
                client = Client(framer, port)
        assert not line.problems, f"{len(line.problems)} wrong answers: {line.problems[:5]}"
        kinds = {type(o).__name__ for _u, _p, o in line.served}
    assert kinds == {"Reply", "Exception02", "Silence"}
