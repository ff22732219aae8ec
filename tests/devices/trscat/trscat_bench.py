"""Test bench for the TRS-CAT: a 1 ms clock, the built-in master if wanted, an event log.

Devices step in rig order (TRS-CAT first, master last, as app/rig.py does). Without a master,
``frames`` makes the bench call ``exchange_frame`` every step as a master would, so the ESM can
be driven by hand with ``request``; ``dc`` makes ``request`` write the DC registers before
INIT -> PREOP and PREOP -> SAFEOP as a DC master does (SYNC0 on, one pulse per step, seed 001
§9.1.1 / §9.2), so the TRS-CAT takes DC-SYNC at PS and runs 1:1 with the bench's frames.
Left out, ``dc`` follows the rig's ``sync_mode`` as the built-in master does (uses_dc in
app/network/files.py): a "free_run" bench leaves 0x0981 at 0, and the device runs FREE-RUN.
``configured`` is the 0xF030 list a master writes in PS (seed 001 §9.2 / §9.3.2; the model
powers up with the §9.3.2 default): the built-in master's init commands, or without a master
the bench's own CoE writes as ``request`` asks PREOP -> SAFEOP.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from typing import Any

from app.network.startup import trscat_list_commands
from devices.ethercat import AlState
from devices.events import Event
from devices.master import EtherCatMaster
from devices.master.network import SlaveDescription
from devices.trscat.catalog import INTEGRATED, expansion_list
from devices.trscat.device import TrsCat
from devices.trscat.sync import MODE_BY_NAME, SYNC0_ACTIVE, SyncMode

STEP_US = 1_000
US = 1_000_000
DETECT_US = 200_000  # devices/trscat/device.py DETECT_BASE_US
PER_SLOT_US = 50_000


def detect_us(slots: int) -> int:
    return DETECT_US + PER_SLOT_US * slots


class Bench:
    def __init__(self, expansions: Sequence[str] = (), master: bool = False,
                 frames: bool = True, step_us: int = STEP_US, seed: int = 3,
                 dc: bool | None = None, configured: Sequence[str] | None = None,
                 **kwargs: Any) -> None:
        self.trs = TrsCat("trscat", random.Random(seed), list(expansions), **kwargs)
        if dc is None:
            dc = MODE_BY_NAME[str(kwargs.get("sync_mode", "dc")).lower()] is SyncMode.DC_SYNC
        self.configured = None if configured is None else \
            [INTEGRATED.ident, *(k.ident for k in expansion_list(configured, "configured"))]
        descriptions = None if self.configured is None else [SlaveDescription(
            0, "", "trscat", None, None, None, 1001, dc, trscat_list_commands(self.configured))]
        self.master = EtherCatMaster("master", random.Random(seed + 1), slaves=[self.trs],
                                     dc_slaves=[dc], descriptions=descriptions) \
            if master else None
        self.dc = dc
        self.frames = frames and not master
        self.step_us = step_us
        self.now = 0
        self.events: list[Event] = []
        self._collect()

    def _collect(self) -> None:
        self.events.extend(self.trs.drain_events())
        if self.master is not None:
            self.events.extend(self.master.drain_events())

    def step(self) -> None:
        self.now += self.step_us
        self.trs.step(self.now)
        if self.master is not None:
            self.master.step(self.now)
        elif self.frames:
            self.trs.exchange_frame(self.now)
        self._collect()

    def run(self, seconds: float) -> None:
        end = self.now + round(seconds * US)
        while self.now < end:
            self.step()

    def run_until(self, cond: Callable[[], bool], limit_s: float = 30.0) -> None:
        end = self.now + round(limit_s * US)
        while not cond():
            assert self.now < end, f"condition not met within {limit_s} s"
            self.step()

    def settle(self) -> None:
        """Past the power-up detection of the TRS bus."""
        self.run_until(lambda: self.trs.od is not None)
        self.step()

    def request(self, target: AlState) -> None:
        if self.dc and self.master is None and target in (AlState.PREOP, AlState.SAFEOP):
            self.configure_dc(SYNC0_ACTIVE, self.step_us * 1000)
        if self.configured is not None and self.master is None and \
                target is AlState.SAFEOP and self.trs.al_state is AlState.PREOP:
            for sub, value in enumerate([len(self.configured), *self.configured]):
                self.trs.write_object(0xF030, sub, value)  # the master's PS init commands
        # A master acknowledges an error flag it reads (AL control bit 4, ETG.1000.6).
        self.trs.request_state(target, ack=bool(self.trs.al_status & 0x10))
        self._collect()

    def configure_dc(self, activation: int, cycle_ns: int) -> None:
        """The master's writes of 0x0981 / 0x09A0 / 0x0990 (start: 100 ms on, as SOEM)."""
        self.trs.configure_dc(activation=activation, sync0_cycle_ns=cycle_ns,
                              start_time_ns=(self.now + 100_000) * 1000)
        self._collect()

    def to_state(self, target: AlState) -> None:
        """Walk the ESM up to ``target`` by hand (PREOP, SAFEOP, OP)."""
        self.settle()
        for state in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
            self.request(state)
            for _ in range(5):  # a few cycles, as a master checks a transition later (§9.2 SO)
                self.step()
            assert self.trs.al_state is state, \
                f"stuck in {self.trs.al_state.label}, code 0x{self.trs.al_status_code:04X}"
            if state is target:
                return

    def apply(self, action: str, module: int | None = None, **args: Any) -> Any:
        result = self.trs.apply(action, args, module)
        self._collect()
        return result

    def read(self, index: int, sub: int) -> Any:
        return self.trs.read_object(index, sub)

    def write(self, index: int, sub: int, value: Any) -> None:
        self.trs.write_object(index, sub, value)
        self._collect()

    def records(self, kind: str | None = None) -> list[dict[str, Any]]:
        out = [e.to_record() for e in self.events]
        return [r for r in out if kind is None or r["event"] == kind]

    def clear(self) -> None:
        self.events.clear()

    def leds(self) -> dict[str, str]:
        return self.trs.snapshot()["leds"]

    def messages(self) -> list[dict[str, Any]]:
        return self.trs.snapshot()["diagnosis"]["messages"]
