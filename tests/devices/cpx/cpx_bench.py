"""Test bench for the CPX-E-EC: a 1 ms clock, the built-in master (optional), an event log.

Devices step in rig order (the slave first, the master last, as app/rig.py does).
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from typing import Any

from app.network.startup import history_flags_command
from devices.cpx.device import CpxEEc
from devices.ethercat import AlState
from devices.events import Event
from devices.master import EtherCatMaster
from devices.master.network import SlaveDescription

STEP_US = 1_000
US = 1_000_000
# The CPX-E system of seed 002 §2.3.2 (Fig. 4 / Tab. 9): modules 1 ... 5 behind the bus
# module, which runs with status bits (DIL 1 off, DIL 2 on).
TAB9_MODULES = ("CPX-E-16DI", "CPX-E-8DO", "CPX-E-8DO", "CPX-E-4AI-U-I", "CPX-E-4AO-U-I")
# DIL 1 on, DIL 2 off (Tab. 6): the I/O diagnostic interface, the one mode in which the CPX-E
# system's error messages (0x10F3, emergencies) reach the PLC (§2.5 note, choice 33).
STI: dict[str, Any] = {"dil1": True, "dil2": False}


class Bench:
    """``history_flags``: 0x10F3:5 as a master's start-up writes it (the model powers up with
    Tab. 14's 0x0000): the built-in master's PS init command, or without a master the bench's
    own CoE write at power-up."""

    def __init__(self, modules: Sequence[Any] = TAB9_MODULES, master: bool = True,
                 seed: int = 5, history_flags: int | None = None, **kwargs: Any) -> None:
        self.cpx = CpxEEc("cpx", random.Random(seed), list(modules), **kwargs)
        startup = () if history_flags is None else (history_flags_command(history_flags),)
        descriptions = [SlaveDescription(0, "", "cpx", None, None, None, 1001, False,
                                         startup)] if startup else None
        self.master = EtherCatMaster("master", random.Random(seed + 1), slaves=[self.cpx],
                                     descriptions=descriptions) if master else None
        if history_flags is not None and not master:
            self.cpx.apply("write_object", {"index": 0x10F3, "sub": 5, "value": history_flags})
        self.now = 0
        self.events: list[Event] = []
        self._collect()

    def _devices(self) -> list[Any]:
        return [self.cpx] + ([self.master] if self.master is not None else [])

    def _collect(self) -> None:
        for device in self._devices():
            self.events.extend(device.drain_events())

    def step(self) -> None:
        self.now += STEP_US
        for device in self._devices():
            device.step(self.now)
        self._collect()

    def run(self, seconds: float) -> None:
        end = self.now + round(seconds * US)
        while self.now < end:
            self.step()

    def run_until(self, done: Callable[[], bool], limit_s: float = 30.0) -> None:
        end = self.now + round(limit_s * US)
        while not done():
            if self.now >= end:
                raise AssertionError(f"condition not reached within {limit_s} s")
            self.step()

    def to_op(self) -> Bench:
        """Until the slave is in OP and the master has confirmed it (no request pending)."""
        def done() -> bool:
            confirmed = self.master is None or self.master.links[0].believed is AlState.OP
            return self.cpx.al_state is AlState.OP and confirmed
        self.run_until(done)
        return self

    def apply(self, action: str, module: int | None = None, **args: Any) -> Any:
        result = self.cpx.apply(action, args, module)
        self._collect()
        return result

    def records(self, kind: str, since: int = 0) -> list[dict[str, Any]]:
        return [e.to_record() for e in self.events[since:] if e.kind == kind]

    def led(self, name: str) -> str:
        return self.cpx.snapshot()["leds"][name]

    def led_state(self, name: str) -> tuple[str, str]:
        state = self.cpx.snapshot()["led_states"][name]
        return state["pattern"], state["colour"]


def tab9(**kwargs: Any) -> Bench:
    """The §2.3.2 system: status bits on, the master brings it to OP."""
    kwargs.setdefault("dil2", True)
    return Bench(TAB9_MODULES, **kwargs)
