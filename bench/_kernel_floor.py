"""The floor CPython sets for stepping a rig one cycle at a time (benchmark 1, issue 7).

A stand-in rig with the real rig's device ids, each model replaced by the least a stepped model
does: take the time of the step. The master stand-in does per cycle the least a master does per
slave on its line: pass it a frame and look into its mailbox (empty). The stand-ins are stepped
by the real :meth:`app.rig.Rig.step` (event collection included), so the figure is what the
loop and the calls alone cost: no model can make a rig step cheaper than this while every
device is stepped every cycle. ``rigs in real time`` is how many such rigs one core could step
at the cycle if the models cost nothing.
"""

from __future__ import annotations

import time
from typing import Any

from app.rig import Rig
from devices.events import EventQueue

STEPS = 100_000


class _Model:
    """A model that does nothing but take the time of each step."""

    def __init__(self, device_id: str) -> None:
        self.device_id = device_id
        self.events = EventQueue()
        self.now_us = 0
        self.frames = 0
        self.mailbox: list[bytes] = []

    def step(self, now_us: int) -> None:
        self.now_us = now_us

    def exchange_frame(self, now_us: int) -> None:
        self.frames += 1
        self.last_frame_us = now_us

    def take_emergencies(self) -> list[bytes]:
        if not self.mailbox:
            return []
        out, self.mailbox = self.mailbox, []
        return out


class _Master(_Model):
    def __init__(self, device_id: str, slaves: list[_Model]) -> None:
        super().__init__(device_id)
        self.slaves = slaves

    def step(self, now_us: int) -> None:
        self.now_us = now_us
        for slave in self.slaves:
            slave.exchange_frame(now_us)
            slave.take_emergencies()


def stand_in(rig: Rig) -> Rig:
    """The floor rig of ``rig``: the same device ids in the same order, the same master line."""
    models: dict[str, Any] = {i: _Model(i) for i in rig.devices}
    for device_id, device in rig.devices.items():
        links = getattr(device, "links", None)
        if links is not None:  # the master: its slaves, by the models they stand for
            slaves = [models[link.slave.device_id] for link in links
                      if link.slave.device_id in models]
            models[device_id] = _Master(device_id, slaves)
    return Rig(f"{rig.name} (floor)", models, seed=rig.seed)


def floor_us(rig: Rig, steps: int = STEPS) -> float:
    """CPU microseconds per step of the stand-in rig of ``rig``."""
    floor = stand_in(rig)
    start = time.process_time()
    for _ in range(steps):
        floor.step()
    return (time.process_time() - start) / steps * 1e6


def floor_line(rig: Rig, step_us: int, steps: int = STEPS) -> str:
    us = floor_us(rig, steps)
    slaves = sum(len(getattr(d, "links", ())) for d in rig.devices.values())
    return (f"    floor: {len(rig.devices)} models that do nothing, {slaves} slave"
            f"{'s' if slaves != 1 else ''} passed a frame per cycle: {us:.1f} us per rig "
            f"step, at most {step_us / us:.0f} rigs in real time")
