"""What a master reads and writes on the drive's Modbus line beyond the seed's worked examples:
the R00 / R05 bits, R46, R48 and the outputs (seed 004 ch. 1 quick reference, ch. 2 "I/O
digitali"), on the real drive model through pymodbus's client, both framings.
"""

from __future__ import annotations

import random
from collections.abc import Iterator

import pytest
from modbus_line import BOOT_US, serve
from own_loop import run
from pymodbus.client import AsyncModbusTcpClient
from pymodbus.framer import FramerType
from sim_helpers import SimThread

from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

EOJ, ALM_ST, LTC_ST = 0x40, 0x08, 0x10


class Master:
    """A pymodbus client at node 1; R00..R133 as 32-bit (quantity 2, high word first)."""

    def __init__(self, client: AsyncModbusTcpClient) -> None:
        self.client = client

    async def write(self, n: int, value: int) -> None:
        word = value & 0xFFFF_FFFF
        reply = await self.client.write_registers(0x8000 + n, [word >> 16, word & 0xFFFF],
                                                  device_id=1)
        assert not reply.isError()

    async def read(self, n: int) -> int:
        reply = await self.client.read_holding_registers(0x8000 + n, count=2, device_id=1)
        assert not reply.isError()
        high, low = reply.registers
        return int.from_bytes((high << 16 | low).to_bytes(4, "big"), "big", signed=True)


@pytest.fixture(params=["socket+call", "rtu+call"], ids=["socket", "rtu"])
def line(request: pytest.FixtureRequest) -> Iterator[tuple[ServoDrive, SimThread, int, str]]:
    drive = ServoDrive("drive", random.Random(1), DriveConfig(node_id=1), MemoryFlash())
    with serve([drive], request.param) as served:
        sim = served.sim
        sim.wait_for(lambda: sim.now_us >= BOOT_US, 2 * BOOT_US)
        yield drive, sim, served.port, served.framer


def session(line, script) -> None:
    drive, sim, port, framer = line

    async def go() -> None:
        client = AsyncModbusTcpClient("127.0.0.1", port=port, framer=FramerType(framer),
                                      timeout=3.0, retries=0)
        await client.connect()
        try:
            await script(Master(client), drive, sim)
        finally:
            client.close()

    run(go())


def set_input(sim: SimThread, drive: ServoDrive, name: str, value: bool) -> None:
    sim.call(lambda: drive.apply("set_input", {"name": name, "value": value}))


def test_a_start_refused_with_ien_low_is_consumed(line) -> None:
    """0x23 with the IEN input low: no move and R00 reads back 0x03 (Pos_str "ritorna
    automaticamente a zero", ch. 2); with IEN back, the master's next 0x23 starts."""
    async def script(m: Master, drive: ServoDrive, sim: SimThread) -> None:
        await m.write(2, 60)
        await m.write(1, 1)
        await m.write(9, 600)
        set_input(sim, drive, "ien", False)
        await m.write(0, 0x03)
        await m.write(0, 0x23)
        assert await m.read(0) == 0x03
        set_input(sim, drive, "ien", True)
        await m.write(0, 0x23)
        sim.wait_for(lambda: drive.read_register(5) & EOJ, 5_000_000)
        sim.wait_for(lambda: drive.read_register(6) == 600, 1_000_000)
        assert await m.read(6) == 600

    session(line, script)


def test_alarm_code_and_reset_on_the_wire(line) -> None:
    """R46 holds the alarm code and R05 bit 3 Alm_st is set; CW = 8 resets once the cause is
    gone (ch. 1, ch. 2 example "valore 8", ch. 3)."""
    async def script(m: Master, drive: ServoDrive, sim: SimThread) -> None:
        sim.call(lambda: drive.apply("inject_alarm", {"code": "16"}))
        assert await m.read(46) == 16
        assert await m.read(5) & ALM_ST
        sim.call(lambda: drive.apply("clear_alarm", {"code": "16"}))
        await m.write(0, 0x08)
        assert await m.read(46) == 0
        assert not await m.read(5) & ALM_ST

    session(line, script)


def test_latch_inputs_and_outputs_on_the_wire(line) -> None:
    """Position latch: R07 and R05 bit 4 after 2 ms high, cleared by Ltc_rst (R00 bit 4);
    R48 bit 0 is pin 11; R49 / R50 drive the End of Job pin as a generic output."""
    async def script(m: Master, drive: ServoDrive, sim: SimThread) -> None:
        set_input(sim, drive, "latch", True)
        assert await m.read(48) & 0x01
        sim.wait_for(lambda: drive.read_register(5) & LTC_ST, 10_000)
        assert await m.read(7) == sim.call(lambda: drive.position_user)
        await m.write(0, 0x10)
        assert not await m.read(5) & LTC_ST
        await m.write(49, 0x01)
        await m.write(50, 0x01)
        assert sim.call(drive.outputs)["end_of_job"]
        await m.write(50, 0x00)
        assert not sim.call(drive.outputs)["end_of_job"]

    session(line, script)
