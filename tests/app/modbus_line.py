"""The drive's Modbus line served for a test: one place for what the Modbus tests share.

A :class:`~app.modbus.server.DriveModbusServer` on 127.0.0.1 (a free port) over a
:class:`~sim_helpers.SimThread`, reached either through the thread's queue (``submit``) or,
as ``python -m app`` does, answered in the server's loop between two steps (``call``); raw
frames in MBAP or RTU framing (seed 004 ch.2); reading a reply off a socket.
"""

from __future__ import annotations

import random
import selectors
import socket
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from pymodbus.client import AsyncModbusTcpClient
from pymodbus.framer import FramerRTU, FramerType
from sim_helpers import SimThread

from app.modbus.server import DriveModbusServer
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

h = bytes.fromhex
SILENCE_S = 0.3  # how long a test waits to call "no reply" silence
REPLY_S = 3.0
BOOT_US = 100_000  # past the drive's power-on self test


def rtu_adu(unit: int, pdu: bytes) -> bytes:
    """``node + PDU + CRC``, the CRC low byte first as the standard puts it on the wire."""
    body = bytes((unit,)) + pdu
    return body + FramerRTU.compute_CRC(body).to_bytes(2, "big")


def receive(sock: socket.socket, wait: float) -> bytes:
    """What came back within ``wait``; stops once the line is quiet after the first bytes."""
    data = b""
    sock.settimeout(wait)
    try:
        while chunk := sock.recv(512):
            data += chunk
            sock.settimeout(0.05)  # a reply is one write: stop once the line is quiet
    except TimeoutError:
        pass
    return data


def servo(node: int) -> ServoDrive:
    """A drive as the default rig has it: on Modbus, TEN and IEN wired to 24 V."""
    return ServoDrive(f"servo{node}", random.Random(node), DriveConfig(node_id=node),
                      MemoryFlash())


@contextmanager
def modbus_server(drives: list, sim: SimThread, framer: str,
                  call: Callable[[Callable[[], Any]], Any] | None = None
                  ) -> Iterator[DriveModbusServer]:
    """The server on ``sim``'s drives, stopped on the way out; ``call`` as the server takes it
    (None: every request through ``sim.submit``)."""
    server = DriveModbusServer(drives, sim.submit, host="127.0.0.1", port=0, framer=framer,
                               call=call)
    server.start_in_thread()
    try:
        yield server
    finally:
        server.stop_in_thread()


@dataclass
class Line:
    server: DriveModbusServer
    sim: SimThread
    drives: list
    framer: str
    trace: list[tuple[bool, bytes]] = field(default_factory=list)

    @property
    def port(self) -> int:
        return self.server.port

    def adu(self, unit: int, pdu: bytes, tid: int = 1) -> bytes:
        """The frame as it travels: RTU ``node + PDU + CRC`` or MBAP ``header + PDU``."""
        if self.framer == "rtu":
            return rtu_adu(unit, pdu)
        return tid.to_bytes(2, "big") + b"\0\0" + (len(pdu) + 1).to_bytes(2, "big") \
            + bytes((unit,)) + pdu

    def seed(self, rtu: str) -> bytes:
        """A seed example, printed as an RTU ADU with its CRC, in this line's framing."""
        adu = h(rtu)
        if self.framer == "rtu":
            return adu
        return self.adu(adu[0], adu[1:-2])

    def exchange(self, frame: bytes, wait: float = REPLY_S) -> bytes:
        """Send raw bytes on a fresh connection; return what came back within ``wait``."""
        with socket.create_connection(("127.0.0.1", self.port), timeout=wait) as sock:
            sock.sendall(frame)
            return receive(sock, wait)

    def exchange_all(self, frames: list[bytes], wait: float = SILENCE_S,
                     expect: list[bytes] | None = None) -> list[bytes]:
        """Send each frame on its own connection, all at once; what came back on each within
        ``wait``, or once each connection got as many bytes as ``expect`` has for it."""
        socks = [socket.create_connection(("127.0.0.1", self.port), timeout=wait)
                 for _ in frames]
        got = [b""] * len(frames)
        with selectors.DefaultSelector() as sel:
            for i, (sock, frame) in enumerate(zip(socks, frames, strict=True)):
                sock.sendall(frame)
                sock.setblocking(False)
                sel.register(sock, selectors.EVENT_READ, i)
            deadline = time.monotonic() + wait
            while (left := deadline - time.monotonic()) > 0:
                if expect is not None and all(
                        len(g) >= len(e) for g, e in zip(got, expect, strict=True)):
                    break
                for key, _ in sel.select(left):
                    chunk = key.fileobj.recv(512)  # type: ignore[union-attr]
                    got[key.data] += chunk
                    if not chunk:
                        sel.unregister(key.fileobj)
        for sock in socks:
            sock.close()
        return got

    def client(self, timeout: float = REPLY_S) -> AsyncModbusTcpClient:
        def trace(sending: bool, data: bytes) -> bytes:
            self.trace.append((sending, bytes(data)))
            return data

        return AsyncModbusTcpClient("127.0.0.1", port=self.port,
                                    framer=FramerType(self.framer), timeout=timeout,
                                    retries=0, trace_packet=trace)


@contextmanager
def serve(drives: list, framer: str, paused: bool = False) -> Iterator[Line]:
    """The line on ``framer``; "socket+call" / "rtu+call" is that framing served through
    ``call`` (answered in the server's loop between two steps, as ``python -m app`` does)
    instead of ``submit``."""
    framer, _, hand_over = framer.partition("+")
    with SimThread(drives, paused=paused) as sim, \
            modbus_server(drives, sim, framer, sim.call if hand_over == "call" else None) as s:
        yield Line(s, sim, drives, framer)
