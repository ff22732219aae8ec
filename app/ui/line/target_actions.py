"""The Line tab's slave forms offer only what their Target takes.

The model says it (``DeviceModel.target_actions``: the action table's ``module`` and, on a
module, its type), asked in the simulation thread as Module I/O asks a FastCAT rail module
(``available_actions``, app/ui/panels/modules.py); the answer is parked and the forms are
restricted in the dashboard thread's next update. Before, ``cpx/2`` listed set_dil, set_rotary
and the device's cable, power and supply, which the device refused once applied.

The Target lists follow the rig the same way: a TRS-CAT expansion plugged (or taken off) after
the dashboard started is offered (or dropped) at the next frame, the pick kept while it
exists. Before, every list was the first snapshot's for good.

A shared form (an open rig's, a :class:`~app.ui.panels.client_action_form.ClientActionForm`)
offers each page what its own Target takes; an instructor's own copy (an ActionForm) what its
own Target picker takes.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from app.runtime import Runtime
from app.targets import parse_target
from app.ui.commands import CommandSender
from app.ui.panels.action_form import ActionForm
from app.ui.panels.client_action_form import ClientActionForm
from app.ui.panels.client_pick import ClientPick
from app.ui.panels.widgets import set_options


def targets(device: str, snap: Mapping[str, Any]) -> list[str]:
    """The device and its parts a command can address: TRS-CAT expansions (slots 1..),
    CPX-E-EC modules (1..)."""
    parts = [int(s.get("slot", 0)) for s in snap.get("slots") or []][1:]
    parts += [int(m.get("module", 0)) for m in snap.get("modules") or []]
    return [device, *(f"{device}/{n}" for n in parts)]


def picked(target: Any, client_id: int | None) -> str:
    """The Target ``client_id``'s page picked (a ClientPick: its own; a plain dropdown, an
    instructor's own copy: its value)."""
    return target.value_for(client_id) if isinstance(target, ClientPick) else str(target.value)


@dataclass
class Watch:
    """A Target picker and the forms acting on what it picks. ``picks``: every Target the
    pages have picked (a ClientPick: each page's own, and a new page's); a ClientActionForm
    offers each page what its own Target takes."""

    device: str
    target: Any
    forms: tuple[ActionForm | ClientActionForm, ...]
    picks: Callable[[], set[str]] | None = None
    # Each Target's actions, for the device's parts as they are (``key``): simulation thread
    known: dict[str, list[str]] = field(default_factory=dict)
    asked: set[str] = field(default_factory=set)
    key: int = 0
    offered: list[str] | None = None

    def picked(self) -> set[str]:
        return self.picks() if self.picks is not None else {str(self.target.value)}


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

    def watch(self, device: str, target: Any, forms: Iterable[ActionForm | ClientActionForm],
              picks: Callable[[], set[str]] | None = None) -> Watch:
        """Restrict ``forms`` to what ``target``'s picks take, now and at each pick."""
        watch = Watch(device, target, tuple(forms), picks)
        if isinstance(target, ClientPick):
            target.on_pick(lambda _client, _picked: self.read(watch))
        else:
            target.on_update(lambda _event: self.read(watch))
        self.read(watch)
        return watch

    def read(self, watch: Watch) -> None:
        """Ask the model about the picked Targets not asked about yet for these parts."""
        with self._lock:
            key = watch.key
            new = watch.picked() - watch.asked
            watch.asked |= new
        runtime = self._runtime
        for picked in sorted(new):

            def ask(picked: str = picked) -> list[str]:
                device_id, module = parse_target(picked)
                return list(runtime.rig.device(device_id).target_actions(module))

            def park(names: list[str], picked: str = picked) -> None:
                with self._lock:
                    if watch.key == key:  # else an answer about parts that changed since
                        watch.known[picked] = names

            self._sender.submit(None, "target actions", ask, done=park)

    def update(self, watches: Iterable[Watch],
               devices: Mapping[str, Mapping[str, Any]] | None) -> None:
        """Per frame: each Target list as the rig has it now, the forms offering what the
        picks take once known; asked again when a device's parts changed."""
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
            # falls back to the device.
            if watch.device in devices:
                options = targets(watch.device, devices[watch.device])
                if isinstance(watch.target, ClientPick):
                    watch.target.set_options(options)
                else:
                    set_options(watch.target, options)
            if watch.device in changed:
                with self._lock:
                    watch.key += 1
                    watch.known.clear()
                    watch.asked.clear()
            self.read(watch)  # a pick no page made (one moved by new options) too
            self._offer(watch)

    def _offer(self, watch: Watch) -> None:
        """Each form offers what its Target takes: a page's own form its page's pick's."""
        with self._lock:
            known = dict(watch.known)
        for form in watch.forms:
            if isinstance(form, ClientActionForm):
                form.restrict_each(lambda client_id: known.get(picked(watch.target, client_id)))
        with self._lock:
            names = known.get(str(getattr(watch.target, "value", "")))
            if names is None or names == watch.offered:
                return
            watch.offered = names
        for form in watch.forms:
            if isinstance(form, ActionForm):
                form.restrict(names)
