"""The Line tab's slave forms offer only what their Target takes.

The model says it (``DeviceModel.target_actions``: the action table's ``module`` and, on a
module, its type), asked in the simulation thread as Module I/O asks a FastCAT rail module
(``available_actions``, app/ui/panels/modules.py); the answer is parked and the forms are
restricted in the dashboard thread's next update. Before, ``cpx/2`` listed set_dil, set_rotary
and the device's cable, power and supply, which the device refused once applied.

The Target lists follow the rig the same way: a TRS-CAT expansion plugged (or taken off) after
the dashboard started is offered (or dropped) at the next frame, the pick kept while it
exists. Before, every list was the first snapshot's for good.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from app.runtime import Runtime
from app.targets import parse_target
from app.ui.commands import CommandSender
from app.ui.panels.action_form import ActionForm
from app.ui.panels.widgets import set_options


def targets(device: str, snap: Mapping[str, Any]) -> list[str]:
    """The device and its parts a command can address: TRS-CAT expansions (slots 1..),
    CPX-E-EC modules (1..)."""
    parts = [int(s.get("slot", 0)) for s in snap.get("slots") or []][1:]
    parts += [int(m.get("module", 0)) for m in snap.get("modules") or []]
    return [device, *(f"{device}/{n}" for n in parts)]


@dataclass
class Watch:
    """A Target picker and the forms acting on what it picks."""

    device: str
    target: Any
    forms: tuple[ActionForm, ...]
    parked: list[str] | None = field(default=None)  # set by the simulation thread


def parts_key(snap: Mapping[str, Any]) -> tuple[Any, ...]:
    """What decides a device's target lists: its modules' / slots' types (a replaced CPX-E
    module, a plugged TRS-CAT expansion)."""
    return tuple((p.get("module", p.get("slot")), p.get("type", p.get("kind")))
                 for key in ("modules", "slots") for p in snap.get(key) or [])


class TargetActions:
    def __init__(self, runtime: Runtime, sender: CommandSender) -> None:
        self._runtime, self._sender = runtime, sender
        self._lock = threading.Lock()
        self._keys: dict[str, tuple[Any, ...]] = {}

    def watch(self, device: str, target: Any, forms: Iterable[ActionForm]) -> Watch:
        """Restrict ``forms`` to what ``target``'s pick takes, now and at each pick."""
        watch = Watch(device, target, tuple(forms))
        target.on_update(lambda _event: self.read(watch))
        self.read(watch)
        return watch

    def read(self, watch: Watch) -> None:
        picked = str(watch.target.value)
        runtime = self._runtime

        def ask() -> list[str]:
            device_id, module = parse_target(picked)
            return list(runtime.rig.device(device_id).target_actions(module))

        def park(names: list[str]) -> None:
            if str(watch.target.value) == picked:  # else a newer pick's answer is coming
                with self._lock:
                    watch.parked = names

        self._sender.submit(None, "target actions", ask, done=park)

    def update(self, watches: Iterable[Watch],
               devices: Mapping[str, Mapping[str, Any]] | None) -> None:
        """Per frame: each Target list as the rig has it now, the parked lists shown; asked
        again when a device's parts changed."""
        devices = devices or {}
        changed = set()
        for device, snap in devices.items():
            key = parts_key(snap)
            if self._keys.setdefault(device, key) != key:
                self._keys[device] = key
                changed.add(device)
        for watch in watches:
            # Every frame, not only on a change of parts: a list built before the first
            # update (an instructor's, from an older snapshot) catches up too. A vanished pick
            # falls back to the device, whose on_update asks for its actions.
            if watch.device in devices:
                set_options(watch.target, targets(watch.device, devices[watch.device]))
            if watch.device in changed:
                self.read(watch)
            with self._lock:
                names, watch.parked = watch.parked, None
            if names is not None:
                for form in watch.forms:
                    form.restrict(names)
