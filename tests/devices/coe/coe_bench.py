"""A drive and its EtherCAT slave on one simulated clock, with a master's hands on them.

The bench steps drive then slave (as the rig does), 1 ms per step, and — while ``cycling`` —
passes one process-data frame per step, as a master's cyclic task does. SDO access goes
through the slave's mailbox as bytes. Nothing here sleeps or touches a socket.
"""

from __future__ import annotations

import random
import struct
from collections.abc import Callable
from dataclasses import dataclass, field

from devices.coe.drive_slave import DriveEcatSlave
from devices.ethercat import AlState
from devices.events import Event
from devices.flash import MemoryFlash
from devices.master import EtherCatMaster
from devices.od import SdoAbort
from devices.servo.drive import DriveConfig, ServoDrive

MS = 1_000
CIA402_ENABLE = (0x0000, 0x0080, 0x0000, 0x0006, 0x0007, 0x000F)  # seed 004 ch. 4 examples
UP = (AlState.PREOP, AlState.SAFEOP, AlState.OP)


@dataclass
class Bench:
    drive: ServoDrive
    slave: DriveEcatSlave
    flash: MemoryFlash
    t_us: int = 0
    cycling: bool = True  # the master sends a process-data frame every step
    reads_mailbox: bool = True  # the bench takes the emergencies (not a master under test)
    events: list[Event] = field(default_factory=list)
    emergencies: list[bytes] = field(default_factory=list)

    def step(self) -> None:
        self.t_us += MS
        self.drive.step(self.t_us)
        self.slave.step(self.t_us)
        if self.cycling:
            self.slave.exchange_frame(self.t_us)
        if self.reads_mailbox:
            self.emergencies += self.slave.take_emergencies()
        self.events += self.drive.drain_events() + self.slave.drain_events()

    def run(self, ms: float) -> None:
        end = self.t_us + round(ms * MS)
        while self.t_us < end:
            self.step()

    def run_until(self, condition: Callable[[], bool], timeout_ms: float) -> float:
        start = self.t_us
        while not condition():
            if self.t_us - start > timeout_ms * MS:
                raise AssertionError(f"condition not met within {timeout_ms} ms")
            self.step()
        return (self.t_us - start) / MS

    # ---- the master's side ---------------------------------------------------------------
    def go(self, *states: AlState) -> None:
        for state in states:
            # A master acknowledges an error flag it reads (AL control bit 4, ETG.1000.6).
            self.slave.request_state(state, ack=bool(self.slave.al_status & 0x10))
            self.step()

    def up_to(self, target: AlState) -> None:
        for state in UP:
            self.go(state)
            if state is target:
                break
        assert self.slave.al_state is target, (self.slave.al_state, hex(self.slave.al_status_code))

    def read(self, index: int, sub: int = 0, signed: bool = False) -> int:
        return int.from_bytes(self.slave.sdo_upload(index, sub), "little", signed=signed)

    def write(self, index: int, sub: int, value: int, size: int) -> None:
        data = (value & (1 << 8 * size) - 1).to_bytes(size, "little")
        self.slave.sdo_download(index, sub, data)
        self.step()

    def abort(self, fn: Callable[[], object]) -> str:
        """The abort code a mailbox access ends with ("ok" if none)."""
        try:
            fn()
        except SdoAbort as exc:
            return f"0x{int(exc.code):08X}"
        return "ok"

    def cw(self, *values: int) -> None:
        for value in values:
            self.write(0x6040, 0, value, 2)

    def outputs(self, fmt: str, *values: int, ms: float = 1) -> None:
        self.slave.write_outputs(struct.pack(fmt, *values))
        self.run(ms)

    def inputs(self, fmt: str) -> tuple:
        data = self.slave.read_inputs()
        assert data is not None, "no valid inputs"
        return struct.unpack(fmt, data)

    def kinds(self, kind: str) -> list[dict]:
        return [e.to_record() for e in self.events if e.kind == kind]


def make_bench(fieldbus: str = "ethercat", boot: bool = True, flash: MemoryFlash | None = None,
               **config: object) -> Bench:
    flash = flash if flash is not None else MemoryFlash()
    drive = ServoDrive("servo", random.Random(7), DriveConfig(fieldbus=fieldbus, **config),
                       flash)
    slave = DriveEcatSlave("servo-ecat", drive, random.Random(3))
    bench = Bench(drive, slave, flash)
    bench.events += drive.drain_events() + slave.drain_events()
    if boot:
        bench.run(60)  # past the drive's self test
    return bench


def with_master(bench: Bench) -> tuple[EtherCatMaster, Callable[[int], None]]:
    """The built-in master on the bench's slave, which now carries the process data instead
    of the bench (``cycling`` off); ``run(ms)`` steps the bench, then the master, each ms."""
    master = EtherCatMaster("master", random.Random(1), slaves=[bench.slave],
                            retry_interval_us=200_000)
    bench.cycling = False

    def run(ms: int) -> None:
        for _ in range(ms):
            bench.step()
            master.step(bench.t_us)

    return master, run
