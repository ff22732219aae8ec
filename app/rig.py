"""A rig: device models on one simulation clock, stepped in a fixed order.

The rig is single-threaded on purpose: whoever owns it (the scenario runner, the runtime's
simulation thread, a test) is the only caller. Devices step in their declared order and the
master last, so a master sees its slaves' state of the same cycle.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from operator import attrgetter
from typing import Any, ClassVar

from app.clock import SimClock
from app.targets import parse_target
from devices.device import CommandError, DeviceModel
from devices.events import LAST_PUT, Event
from devices.names import did_you_mean
from devices.stillness import Backoff

# Fewer quiet steps than this are stepped one by one: asking every device costs about a step.
MIN_SPAN = 2
# An observer's quiet_until(now_us, step_us): it has nothing to do after the steps up to then.
ObserverSpan = Callable[[int, int], int]
FAR_US = 1 << 62  # an observer with nothing due: the devices decide
_QUEUED = attrgetter("events.items")  # a device's queued events (Rig._collect)


@dataclass
class Rig:
    name: str
    devices: dict[str, DeviceModel]
    clock: SimClock = field(default_factory=SimClock)
    seed: int = 0
    # The name of the scenario played on this rig ("" none), set by run_scenario and the
    # player's load: a recording names it (app/recording), or a handed-over file says no demo.
    scenario: str = ""

    # False: advance() steps one step at a time (the quiet-span differential tests).
    SKIP_SPANS: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self.pending: list[Event] = []
        self._quiet = Backoff()
        # Bumped by whatever may change what a snapshot shows: a command, an outside write
        # (touch), a step the devices did not promise quiet. Equal revisions: the devices are
        # as they were, up to the counters quiet steps move (docs/recording.md "Repeated
        # samples").
        self.revision = 0
        self._promised_us = -1  # every device's steps up to here are quiet (quiet_steps)
        self.skipped_steps = 0  # steps advance() skipped in quiet spans (tests look)
        # Scenario loads that made this rig factory-fresh in place (app/player.py
        # reset_in_place): what tells the recorder and the drive plots a new run started.
        # The clock going back does not: a load at 0 s puts nothing back.
        self.loads = 0
        self._put_seen = -1  # LAST_PUT[0] at the last look into the queues (_collect)

    def device(self, device_id: str) -> DeviceModel:
        found = self.devices.get(device_id)
        if found is None:
            raise CommandError(f"no device '{device_id}' in rig '{self.name}' (devices: "
                               f"{self.targets_text()}){did_you_mean(device_id, self.devices)}")
        return found

    def targets_text(self) -> str:
        """The ids a command may target (a device with actions), each side of a device
        named as such: ``drive-can (the CANopen node of drive)``."""
        shown = [f"{i} ({d.part_of()})" if d.part_of() else i
                 for i, d in self.devices.items() if d.ACTIONS]
        return ", ".join(shown) or "none"

    def check(self, target: str, action: str, args: dict[str, Any]) -> dict[str, Any]:
        """Validate a command without running it (scenario files are checked before a run);
        the arguments as the device reads them."""
        device_id, module = parse_target(target)
        return self.device(device_id).check_command(action, args, module)

    def apply(self, target: str, action: str, args: dict[str, Any]) -> Any:
        device_id, module = parse_target(target)
        self.touch()
        try:
            return self.device(device_id).apply(action, args, module)
        finally:
            self._collect()

    def touch(self) -> None:
        """Something changed the devices from outside a step (a command, a protocol adapter's
        write): a new revision, and no promise of quiet steps until the devices are asked
        again."""
        self.revision += 1
        self._promised_us = -1

    def step(self) -> list[Event]:
        """Advance every device by one clock step; return the events of this step in order."""
        now = self.clock.tick()
        for device in self.devices.values():
            device.step(now)
        self._collect()
        out, self.pending = self.pending, []
        if out or now > self._promised_us:
            self.revision += 1
        return out

    def run_until(self, t_us: int) -> list[Event]:
        """Step to the last step at or before ``t_us``; the events in order. Spans in which
        every device is quiet are skipped in one go (:meth:`advance`)."""
        step_us = self.clock.step_us
        return self.advance(max(0, (t_us - self.clock.now_us) // step_us))

    def advance(self, steps: int) -> list[Event]:
        """``steps`` clock steps, the events in order: the same events and the same state as
        ``steps`` calls of :meth:`step`, but a span in which every device is quiet
        (:meth:`DeviceModel.quiet_until`) is skipped in one go (docs/performance.md "Quiet
        spans"). Between the calls nothing may touch the devices, as between steps."""
        events: list[Event] = []
        while steps > 0:
            span = self.quiet_steps(steps)
            if span:
                self.skip(span)
                steps -= span
            else:
                events.extend(self.step())
                steps -= 1
        return events

    def quiet_steps(self, steps: int, also: Iterable[ObserverSpan] = ()) -> int:
        """How many of the next ``steps`` steps may be skipped in one go (:meth:`skip`): 0, or
        at least MIN_SPAN steps in which every device is quiet, and every ``also`` (an
        observer's own ``quiet_until(now_us, step_us)``: the last time up to which it would do
        nothing after a step of a quiet rig) agrees. No side effect on the devices; after a
        "0" the next asks back off (1, 2, 4 .. calls)."""
        span, observed = self.quiet_span(steps, also)
        if observed:  # up to the step before the observer's, which is then stepped
            span -= 1
        return span if span >= MIN_SPAN else 0

    def quiet_span(self, steps: int, also: Iterable[ObserverSpan] = ()) -> tuple[int, bool]:
        """:meth:`quiet_steps`, and the span's end at the step an observer acts on: ``(span,
        True)`` when an observer (``also``) is due at the span's last step, through which
        every device is still quiet. That step may be skipped with the others: a skipped
        quiet step leaves the devices as a real one would and emits nothing, so the caller
        runs its observers after the skip as it would after that step (app/runtime.py)."""
        if steps < MIN_SPAN or not self.SKIP_SPANS or not self._quiet.due():
            return 0, False
        now, step_us = self.clock.now_us, self.clock.step_us
        promised, least = FAR_US, now + MIN_SPAN * step_us
        for device in self.devices.values():
            promised = min(promised, device.quiet_until(step_us))
            if promised < least:
                break
        # What the devices say now replaces what they said before (a device may have been
        # written to since without a touch); a "no" that left some unasked promises nothing.
        self._promised_us = promised if promised >= least else now
        # Back off only when a device said no (asking them costs about a step); an observer's
        # due time (a recorder's sample) says nothing about the steps after it.
        self._quiet.checked(promised >= least)
        if promised < least:
            return 0, False
        quiet, observed = (min(promised, now + steps * step_us) - now) // step_us, False
        for quiet_until in also:
            # The first step after the observer's quiet time is the one it acts on.
            due = max(1, (quiet_until(now, step_us) - now) // step_us + 1)
            if due <= quiet:
                quiet, observed = due, True
        return quiet, observed

    def skip(self, steps: int) -> None:
        """Skip ``steps`` quiet steps, as :meth:`quiet_steps` just gave (or fewer)."""
        step_us = self.clock.step_us
        until = self.clock.now_us + steps * step_us
        for device in self.devices.values():  # the master last: its slaves' frames
            device.skip_to(until, step_us)
        self.clock.now_us = until
        self.skipped_steps += steps

    def take_events(self) -> list[Event]:
        """Events emitted outside a step (by commands), in order."""
        self._collect()
        out, self.pending = self.pending, []
        return out

    def snapshot(self, since: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Every device's snapshot. ``since``: a snapshot of this rig taken at the current
        :attr:`revision`; the devices whose snapshots quiet steps leave alone
        (``QUIET_SNAPSHOT``) are taken from it as they are (the same objects)."""
        kept = (since or {}).get("devices") or {}
        devices = {}
        for i, d in self.devices.items():
            old = kept.get(i) if d.QUIET_SNAPSHOT else None
            devices[i] = old if old is not None else d.snapshot()
        return {"t": self.clock.now_s, "rig": self.name, "devices": devices}

    def _collect(self) -> None:
        put = LAST_PUT[0]
        if put == self._put_seen:
            return  # no queue of the process was put into since the last look
        self._put_seen = put
        devices = self.devices.values()
        # Most steps emit nothing: one C-level pass over the queues finds that (the loop's
        # own bytecode per device cost more than the steps of several idle devices).
        if not any(map(_QUEUED, devices)):
            return
        for device in devices:
            if device.events.items:  # drain only the devices that emitted
                self.pending.extend(device.drain_events())

    def describe(self) -> dict[str, dict[str, Any]]:
        return {i: {"kind": d.KIND, "actions": dict(d.ACTIONS)} for i, d in self.devices.items()}


def sorted_events(events: Iterable[Event]) -> list[Event]:
    """Stable order by simulated time (events of one step keep their emission order)."""
    return sorted(events, key=lambda e: e.t_us)
