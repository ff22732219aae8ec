"""Test bench for the FastCAT coupler and the built-in master: a 1 ms clock and an event log.

Devices step in rig order (coupler first, master last, as app/rig.py does) and their events
are collected in emission order, like the scenario runner prints them. Without the master,
``frames`` stands for its cyclic frames: a frame after every coupler step, as the built-in
master sends them. ``to_state`` turns it on for SAFEOP and OP (a master that asks for them
writes process data; the coupler's SM watchdog wants them, docs/fastcat-coupler.md).
"""

from __future__ import annotations

import datetime as dt
import random
from collections.abc import Callable, Sequence
from typing import Any

from devices.ethercat import AlState
from devices.events import Event
from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash
from devices.master import EtherCatMaster

STEP_US = 1_000
US = 1_000_000
THREE = ("DB16", "AI8D", "AI8C")  # the seed's Sirio example (§4)


def scan_us(n_modules: int) -> int:
    """Power-up / INIT scan length with n modules (docs/fastcat-coupler.md)."""
    return 1_000_000 + (n_modules + 1) * 250_000


class Bench:
    def __init__(self, modules: Sequence[str | tuple[str, dict[str, Any]]] = THREE,
                 flash: MemoryFlash | None = None, master: bool = False, seed: int = 7,
                 epoch: dt.datetime | None = None, **kwargs: Any) -> None:
        rail = [(m, {}) if isinstance(m, str) else m for m in modules]
        self.flash = flash if flash is not None else MemoryFlash()
        self.fc = FastCat("fastcat", random.Random(seed), rail, flash=self.flash, **kwargs)
        self.master = None
        if master:
            extra = {"epoch": epoch} if epoch is not None else {}
            self.master = EtherCatMaster("master", random.Random(seed + 1), slaves=[self.fc],
                                         **extra)
        self.now = 0
        self.frames = False  # the stand-in for the master's cyclic frames (no master only)
        self.events: list[Event] = []
        self._collect()

    def _devices(self) -> list[Any]:
        return [self.fc] + ([self.master] if self.master is not None else [])

    def _collect(self) -> None:
        for device in self._devices():
            self.events.extend(device.drain_events())

    def step(self) -> None:
        self.now += STEP_US
        for device in self._devices():
            device.step(self.now)
        if self.frames and self.master is None:
            self.fc.exchange_frame(self.now)
        self._collect()

    def run(self, seconds: float) -> None:
        self.run_to(self.now + round(seconds * US))

    def run_to(self, t_us: int) -> None:
        while self.now < t_us:
            self.step()

    def run_until(self, cond: Callable[[], bool], limit_s: float = 30.0) -> None:
        end = self.now + round(limit_s * US)
        while not cond():
            assert self.now < end, f"condition not met within {limit_s} s"
            self.step()

    def settle(self) -> None:
        """Run past the power-up scan."""
        self.run_until(lambda: self.fc.booted and self.fc.scan is None)

    def apply(self, action: str, module: int | None = None, **args: Any) -> Any:
        result = self.fc.apply(action, args, module)
        self._collect()
        return result

    def to_state(self, state: AlState) -> None:
        """Walk the ESM up without a master (each request answered at once); from SAFEOP
        on the frames run, and the step's frame is there when OP is asked."""
        self.settle()
        path = [AlState.PREOP, AlState.SAFEOP, AlState.OP]
        for target in path[:path.index(state) + 1]:
            if target is AlState.SAFEOP and self.master is None:
                self.start_frames()
            self.fc.request_state(target)
            self._collect()
        assert self.fc.al_state is state, self.fc.snapshot()

    def start_frames(self) -> None:
        """The master's cyclic frames from now on, this step's frame included."""
        assert self.master is None, "the master sends its own frames"
        self.frames = True
        self.fc.exchange_frame(self.now)

    def records(self, kind: str | None = None, since: int = 0) -> list[dict[str, Any]]:
        return [e.to_record() for e in self.events[since:] if kind is None or e.kind == kind]

    def mark(self) -> int:
        """Index into ``events`` from which later assertions look."""
        return len(self.events)

    def emergencies(self, since: int = 0) -> list[str]:
        return [r["data"] for r in self.records("emergency", since)]

    def led_events(self, since: int = 0) -> list[tuple[float, str, str]]:
        return [(r["t"], r["led"], r["pattern"]) for r in self.records("led", since)]

    def read(self, index: int, sub: int) -> Any:
        return self.apply("read_object", index=index, sub=sub)

    def write(self, index: int, sub: int, value: Any) -> None:
        self.apply("write_object", index=index, sub=sub, value=value)

    def reset_fault(self) -> None:
        """A clean rising edge of 0x5200:1 (§6.17)."""
        self.write(0x5200, 1, 0)
        self.write(0x5200, 1, 1)
