"""The drive's Modbus line over TCP, from real clients (seed 004 ch.2).

Every test runs per framing: MBAP ("socket") and RTU framing over TCP ("rtu", the real drive
speaks RTU). Requests go through pymodbus's AsyncModbusTcpClient, raw sockets (for the seed's
bytes, byte for byte) and Debian's mbpoll (Modbus TCP only: it speaks RTU on serial ports
only). The drives are stepped by tests/app/sim_helpers.SimThread, 1 ms of simulated time per
loop; the server reaches them only through ``submit`` (``call`` in "socket+call"). The line
itself is tests/app/modbus_line.py, shared with the other Modbus tests.
"""

from __future__ import annotations

import asyncio
import re
import socket
import subprocess
from collections.abc import Iterator

import pytest
from modbus_line import BOOT_US, REPLY_S, SILENCE_S, Line, h, receive, serve, servo
from own_loop import run
from pymodbus.client import AsyncModbusTcpClient
from pymodbus.exceptions import ModbusIOException
from sim_helpers import FakeDrive

from app.modbus.server import DriveModbusServer


# ---- the line under test (tests/app/modbus_line.py) ------------------------------------------
@pytest.fixture(params=["socket", "rtu", "socket+call"])
def framer(request: pytest.FixtureRequest) -> str:
    return request.param


@pytest.fixture
def servo_line(framer: str) -> Iterator[Line]:
    with serve([servo(1), servo(5)], framer) as line:
        line.sim.wait_for(lambda: line.sim.now_us >= BOOT_US, 2 * BOOT_US)
        yield line


@pytest.fixture
def paused_servo_line(framer: str) -> Iterator[Line]:
    with serve([servo(1), servo(5)], framer, paused=True) as line:
        line.sim.advance(BOOT_US)
        yield line


@pytest.fixture
def fake_line(framer: str) -> Iterator[Line]:
    drives = [FakeDrive.default(node_id=1), FakeDrive.default(node_id=5)]
    with serve(drives, framer) as line:
        yield line


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
        client, quick = line.client(), line.client(timeout=SILENCE_S)  # quick: for silences
        await client.connect()
        await quick.connect()
        try:
            reply = await client.read_holding_registers(0x8086, count=2, device_id=5)
            assert reply.isError() and reply.exception_code == 2
            with pytest.raises(ModbusIOException):
                await quick.write_register(3, 100, device_id=5)  # out of range: silence
            with pytest.raises(ModbusIOException):
                await quick.read_coils(0, count=1, device_id=5)
            reply = await client.read_holding_registers(3, count=1, device_id=5)
            assert reply.registers == [50]  # the line still works, d3 unchanged
        finally:
            client.close()
            quick.close()

    run(go())


def test_broadcast_writes_every_drive_and_never_answers(fake_line: Line) -> None:
    """ch.2 "Modo BROADCAST": node 0, every drive processes it, no reply."""
    line = fake_line
    broadcasts = ["06 0003 000A", "10 8009 0002 04 0000 03E8", "03 0003 0001"]
    # A broadcast has no reply to wait for: a read of drive 1's d1 behind each, on the same
    # connection, is answered once the broadcast before it was served, and its reply is all
    # that may come back. (Waiting a fixed 0.3 s for silence and then reading the drives
    # failed under load: the server had not read the broadcasts yet.)
    d1 = line.adu(1, h("03 02 0014"), tid=2)
    frames = [line.adu(0, h(pdu)) + line.adu(1, h("03 0001 0001"), tid=2) for pdu in broadcasts]
    assert line.exchange_all(frames, wait=REPLY_S, expect=[d1] * 3) == [d1] * 3
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


def test_a_request_behind_a_broadcast_in_the_same_read_is_answered(fake_line: Line) -> None:
    """ch.2: the master waits the turnaround delay after a broadcast, then sends its next
    request; TCP keeps no pause, and a server that reads its socket late (a loaded machine)
    finds both frames in one read. With RTU framing pymodbus's FramerRTU.decode took the
    whole buffer with the first frame: the request behind the broadcast was lost, and the
    master timed out (the broadcast test failed so under load)."""
    line = fake_line
    both = line.adu(0, h("06 0003 000A")) + line.adu(5, h("03 0003 0001"), tid=2)
    assert line.exchange(both) == line.adu(5, h("03 02 000A"), tid=2)
    write, read = line.adu(1, h("06 0003 000B")), line.adu(1, h("03 0003 0001"), tid=3)
    assert line.exchange(write + read) == write + line.adu(1, h("03 02 000B"), tid=3)


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
            assert receive(sock, SILENCE_S) == b""  # saving: the reply is held back
            assert line.sim.call(lambda: drive.saves) == 1
            line.sim.advance(drive.save_us)
            assert receive(sock, REPLY_S) == line.adu(1, h("10 8000 0002"))


def test_port_in_use_fails_to_start(fake_line: Line) -> None:
    other = DriveModbusServer(fake_line.drives, fake_line.sim.submit, port=fake_line.server.port,
                              framer=fake_line.framer)
    with pytest.raises(RuntimeError):
        other.start_in_thread()


def test_unknown_framer_is_refused() -> None:
    with pytest.raises(ValueError):
        DriveModbusServer([], lambda fn: None, framer="ascii")  # type: ignore[arg-type]


# ---- the seed's examples on the real drive model -----------------------------------------------
# ch.2 "Esempi", as printed, with the CRC the standard puts on the wire (low byte first).
SEED_NODE_5 = [
    ("05 03 00 01 00 03 55 8F", "05 03 06 00 14 00 32 00 32 03 AC"),  # read d1..d3
    ("05 06 00 03 00 0A F8 49", "05 06 00 03 00 0A F8 49"),  # write d3 = 10
    ("05 10 80 09 00 02 04 00 00 03 E8 47 8D", "05 10 80 09 00 02 B9 8E"),  # R09 = 1000
    ("05 03 00 01 00 03 55 8F", "05 03 06 00 14 00 32 00 0A 02 7E"),  # d3 is now 10
    ("05 03 80 09 00 02 3C 4D", "05 03 04 00 00 03 E8 BF 4D"),  # R09 as 32 bits
]


def test_seed_examples_byte_for_byte(servo_line: Line) -> None:
    line = servo_line
    for request_, reply in SEED_NODE_5:
        assert line.exchange(line.seed(request_)) == line.seed(reply), request_


@pytest.mark.parametrize("save, reply", [
    ("05 06 38 02 00 11 E4 E2", "05 06 38 02 00 11 E4 E2"),  # 16 bit: reply identical
    ("05 10 38 02 00 02 04 00 00 00 11 94 8B", "05 10 38 02 00 02 EC EC"),  # 32 bit
])
def test_seed_save_second_method(paused_servo_line: Line, save: str, reply: str) -> None:
    """ch.2 "Secondo metodo di salvataggio": answered at once, then silence during the save."""
    line = paused_servo_line
    drive = line.drives[1]
    read = line.seed("05 03 00 01 00 03 55 8F")
    assert line.exchange(line.seed(save)) == line.seed(reply)
    assert line.exchange(read, wait=SILENCE_S) == b""
    line.sim.advance(5_000_000)  # "tipicamente inferiore ai 5 secondi"
    assert line.exchange(read) == line.seed("05 03 06 00 14 00 32 00 32 03 AC")
    assert line.sim.call(drive.flash.load) is not None


# The positioner set-up of node 01 (ch.2 "Esempio di configurazione dell'asse in modalità
# posizionatore"): register, 32-bit value, the request as printed + CRC.
SETUP = [
    (0x8002, 0x003C, "01 10 80 02 00 02 04 00 00 00 3C 13 A1"),  # feed_constant
    (0x800A, 0x0064, "01 10 80 0A 00 02 04 00 00 00 64 13 FD"),  # profile_acceleration
    (0x800B, 0x0064, "01 10 80 0B 00 02 04 00 00 00 64 D2 31"),  # profile_deceleration
    (0x800C, 0x03E8, "01 10 80 0C 00 02 04 00 00 03 E8 92 82"),  # profile_velocity
    (0x801B, 0x0000, "01 10 80 1B 00 02 04 00 00 00 00 D2 D6"),  # motion_profile_type
    (0x8012, 0x0021, "01 10 80 12 00 02 04 00 00 00 21 D2 A4"),  # homing_method
    (0x8013, 0x0000, "01 10 80 13 00 02 04 00 00 00 00 D3 70"),  # home_offset
    (0x8015, 0x000A, "01 10 80 15 00 02 04 00 00 00 0A D3 5D"),  # homing_slow_speed
    (0x8016, 0x0064, "01 10 80 16 00 02 04 00 00 00 64 12 A4"),  # homing_acceleration
    (0x8000, 0x0008, "01 10 80 00 00 02 04 00 00 00 08 93 AF"),  # CW = 8: reset alarms
    (0x8001, 0x0006, "01 10 80 01 00 02 04 00 00 00 06 D3 A7"),  # mode 6: homing
    (0x8000, 0x0003, "01 10 80 00 00 02 04 00 00 00 03 D2 68"),  # CW = 3: torque, enable
    (0x8000, 0x0043, "01 10 80 00 00 02 04 00 00 00 43 D3 98"),  # CW = 0x43: start homing
]
MOVE = [
    (0x8000, 0x0000, "01 10 80 00 00 02 04 00 00 00 00 92 69"),  # CW = 0: torque off
    (0x8001, 0x0001, "01 10 80 01 00 02 04 00 00 00 01 92 65"),  # mode 1: positioner
    (0x8009, 0x1770, "01 10 80 09 00 02 04 00 00 17 70 5C 17"),  # target_position 6000
    (0x8000, 0x0003, "01 10 80 00 00 02 04 00 00 00 03 D2 68"),  # CW = 3
    (0x8000, 0x0023, "01 10 80 00 00 02 04 00 00 00 23 D3 B0"),  # CW = 0x23: start
]
SAVE_FIRST_METHOD = [
    (0x8000, 0x0000, "01 10 80 00 00 02 04 00 00 00 00 92 69"),  # torque off first
    (0x8001, -50, "01 10 80 01 00 02 04 FF FF FF CE 93 E5"),  # mode -50
    (0x8000, 0x0020, "01 10 80 00 00 02 04 00 00 00 20 93 B1"),  # CW = 0x20: save
]


def test_seed_positioner_homing_move_and_save(servo_line: Line) -> None:
    """The seed's whole node-01 example through pymodbus's client: set-up, homing until status
    word bit 6 (homing OK), the move to 0x1770 until bit 6 (End of Job), position_actual_value
    6000, then save method 1, whose reply comes at the end of the save."""
    line = servo_line
    drive = line.drives[0]

    async def write(client: AsyncModbusTcpClient, steps) -> None:
        for address, value, printed in steps:
            line.trace.clear()
            word = value & 0xFFFF_FFFF
            reply = await client.write_registers(address, [word >> 16, word & 0xFFFF],
                                                 device_id=1)
            assert not reply.isError() and (reply.address, reply.count) == (address, 2)
            sent = [data for sending, data in line.trace if sending]
            assert len(sent) == 1 and _as_printed(line, sent[0], printed), sent

    async def read32(client: AsyncModbusTcpClient, address: int) -> int:
        reply = await client.read_holding_registers(address, count=2, device_id=1)
        return int.from_bytes(b"".join(w.to_bytes(2, "big") for w in reply.registers), "big",
                              signed=True)

    async def go() -> None:
        client = line.client(timeout=REPLY_S)
        await client.connect()
        try:
            await write(client, SETUP)
            line.sim.wait_for(lambda: drive.read_register(5) & 0x40, 60_000_000)
            assert await read32(client, 0x8006) == 0  # home offset 0
            await write(client, MOVE)
            line.sim.wait_for(lambda: drive.read_register(5) & 0x40, 60_000_000)
            assert await read32(client, 0x8006) == 6000
            status = (await client.read_holding_registers(0x8005, count=1, device_id=1))
            assert status.registers[0] & 0x40  # End of Job
            assert line.sim.call(drive.outputs)["end_of_job"]
            patient = line.client(timeout=10.0)  # the save's reply comes at its end
            await patient.connect()
            await write(patient, SAVE_FIRST_METHOD)
            patient.close()
            assert line.sim.call(lambda: drive.responding)
            assert line.sim.call(drive.flash.load) is not None
        finally:
            client.close()

    run(go())


def _as_printed(line: Line, sent: bytes, printed: str) -> bool:
    """Did pymodbus's client send the printed RTU request: the same bytes in RTU, the same unit
    and PDU behind an MBAP header (whatever its transaction id) in MBAP?"""
    adu = h(printed)
    if line.framer == "rtu":
        return sent == adu
    return sent[2:] == line.adu(adu[0], adu[1:-2])[2:]


# ---- bad input against the real drive -----------------------------------------------------------
BAD_REQUESTS = [
    ("05 06 00 03 00 64", None),  # d3 = 100: out of range
    ("05 06 80 05 00 00", None),  # status word: read-only
    ("05 10 80 06 00 02 04 00 00 00 01", None),  # position_actual_value: read-only
    ("05 06 80 00 80 00", None),  # control word 0xFFFF8000 after sign extension
    ("05 06 80 01 00 02", None),  # mode 2 does not exist
    ("05 10 80 09 00 03 06 00 00 00 00 00 00", None),  # FC 16 quantity 3
    ("05 10 80 09 00 02 02 00 00", None),  # byte count 2 for quantity 2
    ("05 03 80 00 00 03", None),  # odd quantity on registers
    ("05 03 00 01 00 7E", None),  # quantity 126
    ("05 01 00 00 00 08", None),  # FC 01
    ("05 2B 0E 01 00", None),  # FC 43 (device identification)
    ("05 06 38 02 00 12", None),  # the save address takes 0x0011 only
    ("06 03 00 01 00 03", None),  # node 6: no such drive
    ("00 03 00 01 00 03", None),  # broadcast read
    ("05 03 00 17 00 01", "05 83 02"),  # no parameter 23
    ("05 06 80 86 00 01", "05 86 02"),  # no R134
]


def test_bad_input_changes_nothing(paused_servo_line: Line) -> None:
    """Bad requests get exception 02 (addresses) or nothing, and leave both drives as they were;
    a good request afterwards is answered."""
    line = paused_servo_line
    before = [line.sim.call(d.snapshot) for d in line.drives]
    frames = [line.adu(h(r)[0], h(r)[1:]) for r, _ in BAD_REQUESTS] + GARBAGE
    expected = [b"" if reply is None else line.adu(h(reply)[0], h(reply)[1:])
                for _, reply in BAD_REQUESTS] + [b""] * len(GARBAGE)
    assert line.exchange_all(frames, wait=1.0) == expected
    assert [line.sim.call(d.snapshot) for d in line.drives] == before
    read = line.seed("05 03 00 01 00 03 55 8F")
    assert line.exchange(read) == line.seed("05 03 06 00 14 00 32 00 32 03 AC")


# ---- mbpoll (Modbus TCP only: its RTU mode needs a serial port) ---------------------------------
@pytest.fixture
def mbpoll_line() -> Iterator[Line]:
    with serve([servo(1), servo(5)], "socket") as line:
        line.sim.wait_for(lambda: line.sim.now_us >= BOOT_US, 2 * BOOT_US)
        yield line


def mbpoll(line: Line, *args: str) -> tuple[int, str, list[bytes], list[bytes]]:
    """Run mbpoll once, verbose; return its exit code, output, frames sent and received."""
    out = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(line.server.port), "-1", "-v",
                          "-o", "0.5", *args], capture_output=True, text=True, timeout=30)
    text = out.stdout + out.stderr
    return out.returncode, text, _frames(text, "[", "]"), _frames(text, "<", ">")


def _frames(text: str, open_: str, close: str) -> list[bytes]:
    """mbpoll -v prints a frame it sends as [05][03]... and one it receives as <05><03>..."""
    cell = re.escape(open_) + "([0-9A-F]{2})" + re.escape(close)
    return [bytes(int(c, 16) for c in re.findall(cell, row))
            for row in text.splitlines() if re.fullmatch(f"({cell})+", row.strip())]


def test_mbpoll_reads_d1_d3(mbpoll_line: Line) -> None:
    """ch.2 "Codice 0x03" example: 05 03 00 01 00 03 -> 05 03 06 00 14 00 32 00 32."""
    code, text, sent, received = mbpoll(mbpoll_line, "-a", "5", "-0", "-r", "1", "-c", "3",
                                        "127.0.0.1")
    assert code == 0, text
    assert [f[6:] for f in sent] == [h("05 03 00 01 00 03")]
    assert [f[6:] for f in received] == [h("05 03 06 00 14 00 32 00 32")]
    assert re.findall(r"\[(\d)\]:\s+(\d+)", text) == [("1", "20"), ("2", "50"), ("3", "50")]


def test_mbpoll_writes_d3_and_target_position(mbpoll_line: Line) -> None:
    """ch.2 "Codice 0x06" (d3 = 10, reply identical) and "Codice 0x10" (R09 = 1000 = 0x03E8,
    reply 05 10 80 09 00 02); mbpoll's 32-bit big-endian type is the drive's word order."""
    line = mbpoll_line
    code, text, sent, received = mbpoll(line, "-a", "5", "-0", "-r", "3", "127.0.0.1", "10")
    assert code == 0, text
    assert [f[6:] for f in sent] == [h("05 06 00 03 00 0A")] == [f[6:] for f in received]
    code, text, sent, received = mbpoll(line, "-a", "5", "-0", "-r", "0x8009", "-t", "4:int",
                                        "-B", "127.0.0.1", "1000")
    assert code == 0, text
    assert [f[6:] for f in sent] == [h("05 10 80 09 00 02 04 00 00 03 E8")]
    assert [f[6:] for f in received] == [h("05 10 80 09 00 02")]
    drive = line.drives[1]
    assert line.sim.call(lambda: (drive.read_parameter(3), drive.read_register(9))) == (10, 1000)
    code, text, _, _ = mbpoll(line, "-a", "5", "-0", "-r", "0x8009", "-t", "4:int", "-B",
                              "127.0.0.1")
    assert code == 0 and re.search(r"\[32777\]:\s+1000", text), text


def test_mbpoll_sees_exception_02_and_silence(mbpoll_line: Line) -> None:
    line = mbpoll_line
    code, text, _, received = mbpoll(line, "-a", "5", "-0", "-r", "0", "127.0.0.1")
    assert code != 0 and "Illegal data address" in text
    assert [f[6:] for f in received] == [h("05 83 02")]
    for args in (["-a", "5", "-0", "-r", "3", "127.0.0.1", "100"],  # out of range
                 ["-a", "7", "-0", "-r", "3", "127.0.0.1"]):  # no drive 7
        code, text, _, received = mbpoll(line, *args)
        assert code != 0 and "timed out" in text and received == [], text
    assert line.sim.call(lambda: line.drives[1].read_parameter(3)) == 50
