"""A rig: device models on one simulation clock, stepped in a fixed order.

The rig is single-threaded on purpose: whoever owns it (the scenario runner, the runtime's
simulation thread, a test) is the only caller. Devices step in their declared order and the
master last, so a master sees its slaves' state of the same cycle.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from app.clock import SimClock
from app.targets import parse_target
from devices.device import CommandError, DeviceModel
from devices.events import Event


@dataclass
class Rig:
    name: str
    devices: dict[str, DeviceModel]
    clock: SimClock = field(default_factory=SimClock)
    seed: int = 0

    def __post_init__(self) -> None:
        self.pending: list[Event] = []

    def device(self, device_id: str) -> DeviceModel:
        found = self.devices.get(device_id)
        if found is None:
            known = ", ".join(self.devices) or "none"
            raise CommandError(f"no device '{device_id}' in rig '{self.name}' (devices: {known})")
        return found

    def check(self, target: str, action: str, args: dict[str, Any]) -> None:
        """Validate a command without running it (scenario files are checked before a run)."""
        device_id, module = parse_target(target)
        self.device(device_id).check_command(action, args, module)

    def apply(self, target: str, action: str, args: dict[str, Any]) -> Any:
        device_id, module = parse_target(target)
        result = self.device(device_id).apply(action, args, module)
        self._collect()
        return result

    def step(self) -> list[Event]:
        """Advance every device by one clock step; return the events of this step in order."""
        now = self.clock.tick()
        for device in self.devices.values():
            device.step(now)
        self._collect()
        out, self.pending = self.pending, []
        return out

    def run_until(self, t_us: int) -> list[Event]:
        events: list[Event] = []
        while self.clock.now_us + self.clock.step_us <= t_us:
            events.extend(self.step())
        return events

    def take_events(self) -> list[Event]:
        """Events emitted outside a step (by commands), in order."""
        self._collect()
        out, self.pending = self.pending, []
        return out

    def snapshot(self) -> dict[str, Any]:
        return {"t": self.clock.now_s, "rig": self.name,
                "devices": {i: d.snapshot() for i, d in self.devices.items()}}

    def _collect(self) -> None:
        for device in self.devices.values():
            if device.events.items:  # most steps emit nothing: skip the drain
                self.pending.extend(device.drain_events())

    def describe(self) -> dict[str, dict[str, Any]]:
        return {i: {"kind": d.KIND, "actions": dict(d.ACTIONS)} for i, d in self.devices.items()}


def sorted_events(events: Iterable[Event]) -> list[Event]:
    """Stable order by simulated time (events of one step keep their emission order)."""
    return sorted(events, key=lambda e: e.t_us)
