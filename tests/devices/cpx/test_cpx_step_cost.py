"""The CPX-E-EC's cheap still-step test and frame are exact (docs/cpx-e-ec.md "Step cost").

- ``CpxEEc.clock_key_now`` (the still step's test, every step) is ``stillness.clock_key`` (the
  methods the step asks): compared at every step of a seeded random run through the clock's
  edges — the Sync Manager watchdog (Tab. 12), the sync error counter (0x10F1:2), LA IN
  traffic, "no master" and the 20 ms U_EL/SEN bridging (Tab. 29);
- ``exchange_frame`` with its calls inline against :class:`PlainCpx`, whose frame is the plain
  one: the same random operations on both (faults of Tab. 12 / 17, power, supply, cable, DC
  faults of the master), every event, snapshot and ``state_key`` compared after each stretch.
"""

from __future__ import annotations

import contextlib
import random
from typing import Any

import pytest
from cpx_bench import TAB9_MODULES, Bench

from devices.cpx.device import SYNC_COUNTER_CAP, SYNC_MISSED_STEP, CpxEEc
from devices.cpx.stillness import clock_key, state_key
from devices.device import CommandError
from devices.ethercat import AlState
from devices.master import EtherCatMaster


class PlainCpx(CpxEEc):
    """The frame of the plain path: reachable(), has_fault() and application_runs asked."""

    def exchange_frame(self, now_us: int) -> None:
        if not self.reachable():
            return
        self.last_frame_us = now_us
        if self.has_fault("watchdog") or not self.application_runs:
            return
        self.last_pd_us = now_us
        if self.esm.state in (AlState.SAFEOP, AlState.OP):
            missed = self.has_fault("sync_error")
            self.sync_counter = min(SYNC_COUNTER_CAP, self.sync_counter + SYNC_MISSED_STEP) \
                if missed else max(0, self.sync_counter - 1)


OPS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("inject_fault", {"fault": "watchdog"}), ("clear_fault", {"fault": "watchdog"}),
    ("inject_fault", {"fault": "sync_error"}), ("clear_fault", {"fault": "sync_error"}),
    ("inject_fault", {"fault": "ac_failure"}), ("clear_fault", {"fault": "ac_failure"}),
    ("power", {"on": False}), ("power", {"on": True}),
    ("supply", {"el_sen": 5.0}), ("supply", {"el_sen": 24.0}),
    ("cable", {"port": "in", "connected": False}), ("cable", {"port": "in", "connected": True}),
    ("set_dil", {"dil1": True, "dil2": True}), ("set_dil", {"dil1": False, "dil2": True}),
    ("restart", {}),
)
MASTER_OPS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("dc_fault", {"kind": "jitter"}), ("dc_fault", {"kind": "sync0_lost"}),
    ("clear_dc_fault", {}), ("power_slave", {"position": 0, "on": False}),
    ("power_slave", {"position": 0, "on": True}),
)


def operate(bench: Bench, rng: random.Random) -> None:
    assert bench.master is not None
    if rng.random() < 0.3:  # back to a line that reaches OP, where the frames do most
        for action, args in (("power", {"on": True}), ("supply", {"el_sen": 24.0}),
                             ("cable", {"port": "in", "connected": True}),
                             ("clear_fault", {"fault": "ac_failure"}),
                             ("clear_fault", {"fault": "watchdog"})):
            with contextlib.suppress(CommandError):  # a fault not injected
                bench.cpx.apply(action, args)
        if bench.cpx.switches.dil1:  # out of the bootloader (DIL 1 + 2, Tab. 6)
            bench.cpx.apply("set_dil", {"dil1": False, "dil2": True})
            bench.cpx.apply("restart", {})
        bench.master.apply("power_slave", {"position": 0, "on": True})
        bench.master.apply("clear_dc_fault", {})
        return
    with contextlib.suppress(CommandError):
        if rng.random() < 0.25:
            action, args = rng.choice(MASTER_OPS)
            bench.master.apply(action, args)
        else:
            action, args = rng.choice(OPS)
            bench.cpx.apply(action, args)


class PlainBench(Bench):
    """cpx_bench.Bench (seed 5, the modules of Tab. 9, the master) around a PlainCpx."""

    def __init__(self) -> None:
        self.cpx = PlainCpx("cpx", random.Random(5), list(TAB9_MODULES))
        self.master = EtherCatMaster("master", random.Random(6), slaves=[self.cpx])
        self.now = 0
        self.events = []
        self._collect()


def random_run(bench: Bench, seed: int, check_clock: bool = False) -> list[Any]:
    rng = random.Random(seed)
    out: list[Any] = []
    compared = 0
    for _ in range(60):
        operate(bench, rng)
        for _ in range(rng.choice((1, 5, 30, 120, 400, 2500))):
            bench.step()
            if check_clock:
                assert bench.cpx.clock_key_now() == clock_key(bench.cpx), bench.now
                compared += 1
        out.append((bench.now, bench.cpx.snapshot(), state_key(bench.cpx)))
    if check_clock:
        assert compared > 1000
    return out + [e.to_record() for e in bench.events]


@pytest.mark.parametrize("seed", range(3))
def test_clock_key_now_is_clock_key(seed: int) -> None:
    random_run(Bench(), seed, check_clock=True)


@pytest.mark.parametrize("seed", range(3))
def test_the_frame_is_the_plain_one(seed: int) -> None:
    fast = random_run(Bench(), seed)
    assert fast == random_run(PlainBench(), seed)
    states = {snap["esm"] for _t, snap, _k in fast[:60]}
    assert "OP" in states and len(states) > 1
