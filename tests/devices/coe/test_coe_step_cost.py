"""The CoE slave's cheap step and frame are exact (docs/ethercat-coe.md "Step cost"; issue 7).

``DriveEcatSlave.step`` tests inline what ``_follow_power``, ``_check_watchdog`` and
``_refresh`` test first, and ``exchange_frame`` reads the ESM's rank from a set: a seeded
random differential against :class:`PlainSlave`, whose step and frame are the calls as they
were before (the plain path), over the ESM walk (seed 004 ch. 5, ETG.1000.6), process data,
the SM watchdog (no frames), drive alarms (EMCY), the cable and the drive's power; every
event, emergency, snapshot and input image compared after each stretch.
"""

from __future__ import annotations

import contextlib
import random
from typing import Any

import pytest
from coe_bench import Bench

from devices.coe.drive_slave import DriveEcatSlave
from devices.device import CommandError, DeviceModel
from devices.ethercat import AlState
from devices.events import EmergencySent
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive


class PlainSlave(DriveEcatSlave):
    """The step and frame of the plain path: every test in its own call."""

    def step(self, now_us: int) -> None:
        DeviceModel.step(self, now_us)
        self._follow_power()
        drive = self.drive
        if self.on_line:
            self._check_watchdog()
            self._check_controller()
            seen = drive.alarms.latched if drive.powered else []
            if seen != self.emergencies.known and self.esm.at_least(AlState.PREOP):
                for frame in self.emergencies.watch(drive):
                    self.emit(EmergencySent(now_us, self.drive.device_id,
                                            code=int.from_bytes(frame[:2], "little"),
                                            register=frame[2], data=frame[3:]))
        self._refresh()

    def exchange_frame(self, now_us: int) -> None:
        if not self.reachable():
            return
        self.last_frame_us = now_us
        self.frames += 1
        if self.esm.state is AlState.OP and self.outputs is not None:
            self._apply_outputs(self.outputs)
        self._inputs_due = self.esm.at_least(AlState.SAFEOP)


def bench_of(cls: type[DriveEcatSlave]) -> Bench:
    """coe_bench.make_bench(boot=False) with a slave of ``cls``."""
    drive = ServoDrive("servo", random.Random(7), DriveConfig(fieldbus="ethercat"),
                       MemoryFlash())
    slave = cls("servo-ecat", drive, random.Random(3))
    bench = Bench(drive, slave, drive.flash)
    bench.events += drive.drain_events() + slave.drain_events()
    return bench


def operate(bench: Bench, rng: random.Random) -> None:
    slave, drive = bench.slave, bench.drive
    op = rng.randrange(10)
    if op <= 1 and not (slave.link and drive.powered):  # mostly back on the line
        op = 4 if not slave.link else 5
    if op <= 1:  # the master's walk: the next state up
        up = {AlState.INIT: AlState.PREOP, AlState.PREOP: AlState.SAFEOP}
        slave.request_state(up.get(slave.esm.state, AlState.OP),  # acknowledging (bit 4)
                            ack=bool(slave.al_status & 0x10))
    elif op == 2:
        slave.request_state(rng.choice((AlState.INIT, AlState.PREOP, AlState.SAFEOP)))
    elif op == 3 or (op == 9 and not bench.cycling):
        bench.cycling = not bench.cycling  # no frames: the SM watchdog runs out
    elif op == 4:
        slave.set_link(not slave.link or rng.random() < 0.5)
    elif op == 5:
        drive.apply("power", {"on": not drive.powered or rng.random() < 0.5})
    elif op == 6:
        action = rng.choice(("inject_alarm", "clear_alarm"))
        with contextlib.suppress(CommandError):
            drive.apply(action, {"code": rng.choice(("4", "16", "7"))})
    elif op == 7:
        with contextlib.suppress(CommandError):
            drive.apply("alarm_reset", {})
    else:
        with contextlib.suppress(CommandError):  # the image of the assigned RxPDOs
            size = len(slave.outputs) if slave.outputs is not None else 6
            slave.write_outputs(rng.choice((0x06, 0x07, 0x0F, 0x00)).to_bytes(2, "little")
                                + bytes(size - 2))


def run(bench: Bench, seed: int) -> list[Any]:
    rng = random.Random(seed)
    out: list[Any] = []
    for _ in range(150):
        operate(bench, rng)
        bench.run(rng.choice((1, 3, 20, 60, 150)))
        inputs = bench.slave.read_inputs()
        out.append((bench.t_us, bench.slave.snapshot(), inputs, bench.slave.frames))
    return out + [e.to_record() for e in bench.events] + bench.emergencies


@pytest.mark.parametrize("seed", range(4))
def test_the_step_and_frame_are_the_plain_ones(seed: int) -> None:
    result = run(bench_of(DriveEcatSlave), seed)
    assert result == run(bench_of(PlainSlave), seed)
    states = {snap["esm"] for _t, snap, _i, _f in result[:150]}
    assert {"OP", "SAFEOP"} <= states  # the walk reached process data
