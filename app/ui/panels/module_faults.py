"""The instructor's module fault form (FastCAT tab, folder Module I/O), one per connection.

With a token, the module actions that make a fault (``roles.makes_faults``: module_failure,
output_short, encoder_fault, calibrated, inject_fault, ...) leave the shared Module I/O form:
a shared form sent them and the instructor's pick of one to every trainee's page, and its
target was the shared Module picker, so picking the module to fail moved every page's. Each
instructor connection gets this form instead, with a Module picker of its own
(app/ui/panels/per_client.py; docs/classroom.md). An open rig keeps the one shared form.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import viser

from app.runtime import Runtime
from app.ui.commands import CommandSender
from app.ui.panels.action_form import ActionForm
from app.ui.panels.control import module_options, option_slot
from app.ui.panels.per_client import Instructor
from app.ui.panels.widgets import set_options
from devices.device import Action

Rail = Callable[[], Sequence[Mapping[str, Any]]]


class _Copy:
    """One connection's picker and form, and the actions its module takes (once read).

    Its readers of the pick and the rail are the picker's callback (viser's threads) and the
    frame update of a rail change; each parks what the module takes (at once for an empty
    slot, else from the simulation thread). ``lock`` holds each read, the number it takes
    (``asked``) and each park: only the newest read parks. Before, a pick of the empty slot 3
    that read the rail before a DO16 was plugged there parked "nothing" over the frame
    update's DO16 actions, and the form offered "(none)" until the pick or the rail changed."""

    def __init__(self) -> None:
        self.module: Any = None
        self.form: ActionForm | None = None
        self.available: list[str] | None = None  # parked by the simulation thread
        self.asked = 0
        self.lock = threading.Lock()


class ModuleFaults:
    def __init__(
        self,
        instructor: Instructor,
        runtime: Runtime,
        sender: CommandSender,
        device_id: str,
        actions: Mapping[str, Action],
        rail: Rail,
    ) -> None:
        self._runtime, self._sender, self._id = runtime, sender, device_id
        self._actions = dict(actions)
        self._rail = rail
        self._part = instructor.part(self._build)

    def _build(self, gui: Any) -> _Copy:
        copy = _Copy()
        with gui.add_folder("Module faults", expand_by_default=False):
            copy.module = gui.add_dropdown(
                "Module", self._options(), hint="the module the fault goes on"
            )
            copy.form = ActionForm(
                gui,
                self._actions,
                lambda client, name, args: self._apply(copy, client, name, args),
                label="Fault action",
            )
        copy.module.on_update(lambda _event: self._read(copy))
        self._read(copy)
        return copy

    def _apply(
        self, copy: _Copy, client: viser.ClientHandle | None, action: str, args: dict[str, Any]
    ) -> None:
        slot = option_slot(str(copy.module.value))
        if slot is not None:
            self._sender.send(client, f"{self._id}/{slot}", action, args, confirm=True)

    def _read(self, copy: _Copy) -> None:
        """Ask the model which actions the picked module takes (its type decides)."""
        with copy.lock:
            copy.asked += 1
            asked = copy.asked
            slot = option_slot(str(copy.module.value))
            entry = next((e for e in self._rail() if e.get("slot") == slot), None)
        if slot is None or not (entry and entry.get("type")):
            self._park(copy, asked, [])
            return
        device = self._id

        def read() -> list[str]:
            return list(self._runtime.rig.device(device).rail_module(slot).available_actions())

        self._sender.submit(
            None, "module actions", read, done=lambda names: self._park(copy, asked, names)
        )

    def _park(self, copy: _Copy, asked: int, names: list[str]) -> None:
        with copy.lock:
            if asked == copy.asked:  # else a newer read of the pick or the rail parks
                copy.available = names

    def _options(self) -> tuple[str, ...]:
        return tuple(module_options(list(self._rail()))) or ("1",)

    def update(self, rail_changed: bool) -> None:
        """Per frame: new rail options (then a new read), and the parked actions shown.
        Every copy whose options are not the rail's, not only on the frame the rail changed:
        a copy built from the rail before that frame and stored after it (the promote runs
        on another thread) kept the old options until the rail changed again."""
        options = self._options()
        for copy in self._part.each():
            if rail_changed or tuple(copy.module.options) != options:
                set_options(copy.module, list(options))
                self._read(copy)
            with copy.lock:
                available, copy.available = copy.available, None
            if available is not None and copy.form is not None:
                copy.form.restrict(available)
