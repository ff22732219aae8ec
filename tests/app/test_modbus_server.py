"""The drive's Modbus line over TCP, from real clients (seed 004 ch.2).

Every test runs per framing: MBAP ("socket") and RTU framing over TCP ("rtu", the real drive
speaks RTU). Requests go through pymodbus's AsyncModbusTcpClient, raw sockets (for the seed's
bytes, byte for byte) and Debian's mbpoll (Modbus TCP only: it speaks RTU on serial ports
only). The drives are stepped by tests/app/sim_helpers.SimThread, 1 ms of simulated time per
loop; the server reaches them only through ``submit``.
"""

from __future__ import annotations

import asyncio
import socket
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import pytest
from pymodbus.client import AsyncModbusTcpClient
from pymodbus.exceptions import ModbusIOException
from pymodbus.framer import FramerRTU, FramerType
from sim_helpers import FakeDrive, SimThread

from app.modbus.server import DriveModbusServer

h = bytes.fromhex
SILENCE_S = 0.3  # how long a test waits to call "no reply" silence
REPLY_S = 3.0


# ---- the line under test ---------------------------------------------------------------------
@dataclass
class Line:
    server: DriveModbusServer
    sim: SimThread
    drives: list
    framer: str
    trace: list[tuple[bool, bytes]] = field(default_factory=list)

    def adu(self, unit: int, pdu: bytes, tid: int = 1) -> bytes:
        """The frame as it travels: RTU ``node + PDU + CRC`` or MBAP ``header + PDU``."""
        if self.framer == "rtu":
            body = bytes((unit,)) + pdu
            return body + FramerRTU.compute_CRC(body).to_bytes(2, "big")
        return tid.to_bytes(2, "big") + b"\0\0" + (len(pdu) + 1).to_bytes(2, "big") \
            + bytes((unit,)) + pdu

    def exchange(self, frame: bytes, wait: float = REPLY_S) -> bytes:
        """Send raw bytes on a fresh connection; return what came back within ``wait``."""
        with socket.create_connection(("127.0.0.1", self.server.port), timeout=wait) as sock:
            sock.sendall(frame)
            return _receive(sock, wait)

    def client(self, timeout: float = REPLY_S) -> AsyncModbusTcpClient:
        def trace(sending: bool, data: bytes) -> bytes:
            self.trace.append((sending, bytes(data)))
            return data

        return AsyncModbusTcpClient("127.0.0.1", port=self.server.port,
                                    framer=FramerType(self.framer), timeout=timeout,
                                    retries=0, trace_packet=trace)


def _receive(sock: socket.socket, wait: float) -> bytes:
    data = b""
    sock.settimeout(wait)
    try:
        while chunk := sock.recv(512):
            data += chunk
            sock.settimeout(0.05)  # a reply is one write: stop once the line is quiet
    except TimeoutError:
        pass
    return data


@contextmanager
def serve(drives: list, framer: str, paused: bool = False) -> Iterator[Line]:
    with SimThread(drives, paused=paused) as sim:
        server = DriveModbusServer(drives, sim.submit, host="127.0.0.1", port=0, framer=framer)
        server.start_in_thread()
        try:
            yield Line(server, sim, drives, framer)
        finally:
            server.stop_in_thread()


@pytest.fixture(params=["socket", "rtu"])
def framer(request: pytest.FixtureRequest) -> str:
    return request.param


@pytest.fixture
def fake_line(framer: str) -> Iterator[Line]:
    drives = [FakeDrive.default(node_id=1), FakeDrive.default(node_id=5)]
    with serve(drives, framer) as line:
        yield line


def run(coro):
    return asyncio.run(coro)


# ---- framing: the PDU layer's outcomes on the wire -------------------------------------------
def test_reply_exception_and_silence_on_the_wire(fake_line: Line) -> None:
    """ch.2 "Eccezioni": a reply, exception 02 (FC + 0x80, one data byte), or nothing."""
    line = fake_line
    assert line.exchange(line.adu(5, h("03 0001 0003"))) == line.adu(5, h("03 06 0014 0032 0032"))
    assert line.exchange(line.adu(5, h("03 0000 0001"))) == line.adu(5, h("83 02"))
    assert line.exchange(line.adu(5, h("03 0001 0000")), wait=SILENCE_S) == b""


@pytest.mark.parametrize("unit", [2, 90, 91, 255])
def test_unit_id_of_no_drive_is_silent(fake_line: Line, unit: int) -> None:
    """pymodbus answers exception 04 to an unknown device id; the drive line stays silent."""
    line = fake_line
    assert line.exchange(line.adu(unit, h("03 0001 0001")), wait=SILENCE_S) == b""


@pytest.mark.parametrize("pdu", ["01 0000 0001", "02 0000 0001", "04 0000 0001",
                                 "05 0000 FF00", "0F 0000 0001 01 01", "08 0000 1234",
                                 "2B 0E 01 00", "11", "17 0001 0001 0001 0001 02 0001"])
def test_unknown_function_codes_are_silent(fake_line: Line, pdu: str) -> None:
    """ch.2: FC 03, 06, 16 only; pymodbus itself would answer most of these."""
    line = fake_line
    before = [line.sim.call(d.state) for d in line.drives]
    assert line.exchange(line.adu(5, h(pdu)), wait=SILENCE_S) == b""
    assert [line.sim.call(d.state) for d in line.drives] == before


def test_pymodbus_client_sees_exception_02_and_timeouts(fake_line: Line) -> None:
    line = fake_line

    async def go() -> None:
        client = line.client(timeout=SILENCE_S)
        await client.connect()
        try:
            reply = await client.read_holding_registers(0x8086, count=2, device_id=5)
            assert reply.isError() and reply.exception_code == 2
            with pytest.raises(ModbusIOException):
                await client.write_register(3, 100, device_id=5)  # out of range: silence
            with pytest.raises(ModbusIOException):
                await client.read_coils(0, count=1, device_id=5)
            reply = await client.read_holding_registers(3, count=1, device_id=5)
            assert reply.registers == [50]  # the line still works, d3 unchanged
        finally:
            client.close()

    run(go())


def test_broadcast_writes_every_drive_and_never_answers(fake_line: Line) -> None:
    """ch.2 "Modo BROADCAST": node 0, every drive processes it, no reply."""
    line = fake_line
    assert line.exchange(line.adu(0, h("06 0003 000A")), wait=SILENCE_S) == b""
    assert line.exchange(line.adu(0, h("10 8009 0002 04 0000 03E8")), wait=SILENCE_S) == b""
    assert line.exchange(line.adu(0, h("03 0003 0001")), wait=SILENCE_S) == b""
    assert [line.sim.call(lambda d=d: d.read_parameter(3)) for d in line.drives] == [10, 10]
    assert [line.sim.call(lambda d=d: d.read_register(9)) for d in line.drives] == [1000, 1000]

    async def go() -> None:
        client = line.client()
        await client.connect()
        try:
            await client.write_register(3, 11, device_id=0, no_response_expected=True)
            # The master waits the turnaround delay after a broadcast (ch.2, 100-200 ms): an
            # RTU receiver tells frames apart by the silence between them.
            await asyncio.sleep(0.15)
            reply = await client.read_holding_registers(3, count=1, device_id=1)
            assert reply.registers == [11]
        finally:
            client.close()

    run(go())


GARBAGE = [
    b"\x00",
    b"\xff" * 40,
    bytes(range(256)),
    h("05 03 00 01 00 03 00 00"),  # RTU frame with a wrong CRC
    h("00 01 00 00 00 06 05 03 00 01"),  # MBAP header promising more than comes
    h("00 01 00 07 00 06 05 03 00 01 00 03"),  # MBAP protocol id 7
    h("00 01 00 00 00 00 05"),
    h("00 01 00 00 00 01 05"),  # MBAP with a unit id and no PDU
]


@pytest.mark.parametrize("garbage", GARBAGE, ids=range(len(GARBAGE)))
def test_garbage_gets_no_reply_and_the_line_survives(fake_line: Line, garbage: bytes) -> None:
    """ch.2: frames with communication errors are discarded without a reply."""
    line = fake_line
    before = [line.sim.call(d.state) for d in line.drives]
    assert line.exchange(garbage, wait=SILENCE_S) == b""
    assert [line.sim.call(d.state) for d in line.drives] == before
    assert line.exchange(line.adu(5, h("03 0001 0001"))) == line.adu(5, h("03 02 0014"))


def test_save_second_method_answers_then_the_drive_is_silent(framer: str) -> None:
    """ch.2 "Salvataggio su flash": the drive answers the 0x3802 command at once, then does
    not answer while it saves (a few seconds), then answers again."""
    drive = FakeDrive.default(node_id=5)
    with serve([drive], framer, paused=True) as line:
        save = line.adu(5, h("06 3802 0011"))
        assert line.exchange(save) == save
        assert line.exchange(line.adu(5, h("03 0001 0001")), wait=SILENCE_S) == b""
        line.sim.advance(drive.save_us)
        assert line.exchange(line.adu(5, h("03 0001 0001"))) == line.adu(5, h("03 02 0014"))
        assert drive.saves == 1


def test_save_first_method_answers_at_the_end(framer: str) -> None:
    """ch.2 "Primo metodo di salvataggio": the reply to control word 0x20 in mode -50 comes
    when the save is over ("giungerà con un certo ritardo, tipicamente inferiore ai 5 s")."""
    drive = FakeDrive.default(node_id=1)
    with serve([drive], framer, paused=True) as line:
        mode = line.adu(1, h("10 8001 0002 04 FFFF FFCE"))
        assert line.exchange(mode) == line.adu(1, h("10 8001 0002"))
        start = line.adu(1, h("10 8000 0002 04 0000 0020"))
        with socket.create_connection(("127.0.0.1", line.server.port), timeout=5) as sock:
            sock.sendall(start)
            assert _receive(sock, SILENCE_S) == b""  # saving: the reply is held back
            assert line.sim.call(lambda: drive.saves) == 1
            line.sim.advance(drive.save_us)
            assert _receive(sock, REPLY_S) == line.adu(1, h("10 8000 0002"))


def test_port_in_use_fails_to_start(fake_line: Line) -> None:
    other = DriveModbusServer(fake_line.drives, fake_line.sim.submit, port=fake_line.server.port,
                              framer=fake_line.framer)
    with pytest.raises(RuntimeError):
        other.start_in_thread()


def test_unknown_framer_is_refused() -> None:
    with pytest.raises(ValueError):
        DriveModbusServer([], lambda fn: None, framer="ascii")  # type: ignore[arg-type]


# ---- mbpoll (Modbus TCP) ---------------------------------------------------------------------
def mbpoll(port: int, *args: str) -> str:
    out = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(port), "-1", "-v", "-o", "1",
                          *args], capture_output=True, text=True, timeout=20)
    return out.stdout + out.stderr


def _frames(text: str, open_: str) -> list[bytes]:
    """mbpoll -v prints what it sends as [05][03]... and what it receives as <05><03>..."""
    close = "]" if open_ == "[" else ">"
    out = []
    for row in text.splitlines():
        if row.startswith(open_ + "0") or row.startswith(open_):
            cells = [c for c in row.replace(close, " ").replace(open_, " ").split() if c]
            try:
                out.append(bytes(int(c, 16) for c in cells))
            except ValueError:
                continue
    return out
