"""Helpers for the servo drive tests: a drive on a simulated clock, stepped in 1 ms ticks."""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass, field

from devices.events import Event
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

MS = 1_000


@dataclass
class Sim:
    drive: ServoDrive
    flash: MemoryFlash
    t_us: int = 0
    events: list[Event] = field(default_factory=list)

    def run(self, ms: float) -> None:
        self.t_us += round(ms * MS)
        self.drive.step(self.t_us)
        self.events += self.drive.drain_events()

    def run_until(self, condition: Callable[[], bool], timeout_ms: float, tick_ms: float = 1
                  ) -> float:
        """Step until condition() holds; return the simulated ms it took (fail on timeout)."""
        start = self.t_us
        while not condition():
            if self.t_us - start > timeout_ms * MS:
                raise AssertionError(f"condition not met within {timeout_ms} ms")
            self.run(tick_ms)
        return (self.t_us - start) / MS

    def w(self, n: int, value: int) -> None:
        """A register write as the seed's examples do it, then one tick."""
        self.drive.write_register(n, value)
        self.run(1)

    def cw(self, *values: int) -> None:
        """0x6040 writes, one tick apart (a CANopen master's SDO sequence)."""
        for value in values:
            self.drive.write_controlword(value)
            self.run(1)

    @property
    def r05(self) -> int:
        return self.drive.read_register(5)

    def kinds(self, kind: str) -> list[dict]:
        return [e.to_record() for e in self.events if e.kind == kind]

    def run_into_ls1(self) -> None:
        """Homing method 1 (R18, which makes pin 8 a limit switch), mode 3 (velocity),
        R13 = -150000, R00 = 3: the carriage runs into the negative limit switch and raises
        alarm 20 LS1 (seed 004 ch. 5)."""
        self.w(18, 1)
        self.w(1, 3)
        self.w(13, -150000)
        self.w(0, 3)
        self.run_until(lambda: self.drive.read_register(46) == 20, 5_000)


def make_sim(config: DriveConfig | None = None, flash: MemoryFlash | None = None,
             boot: bool = True) -> Sim:
    flash = flash if flash is not None else MemoryFlash()
    drive = ServoDrive("servo", random.Random(7), config or DriveConfig(), flash)
    sim = Sim(drive, flash)
    sim.events += drive.drain_events()
    if boot:
        sim.run(60)  # past the self test: Switch on disabled
    return sim


CANOPEN_ENABLE = (0x0000, 0x0080, 0x0000, 0x0006, 0x0007, 0x000F)  # seed 004 ch. 4 examples
