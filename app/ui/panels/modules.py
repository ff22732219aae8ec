"""Module controls: pick a slot, unplug / plug / swap it, power it, drive its I/O and encoders.

What an operator does to the rail with their hands (seed 000 §2: modules can be plugged,
unplugged and swapped; the coupler notices at the next scan or, in OP, at once) goes through
the FastCAT's module actions on the target ``<device>/<slot>``. AX2 modules get an encoder
section: shaft speed per encoder and the zero-cycle command bits of 0x7600 (§6.30, bits 12 /
13), written with ``write_object`` like a PLC would write its output.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import viser

from app.classroom.roles import makes_faults
from app.runtime import Runtime
from app.ui.commands import CommandSender
from app.ui.panels.action_form import ActionForm
from app.ui.panels.control import module_options, option_slot
from app.ui.panels.module_faults import ModuleFaults
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import Synced, set_options
from app.ui.style import esc
from devices.device import Action
from devices.fastcat.encoder import CMD_ZERO_CYCLE, COMMAND_INDEX
from devices.fastcat.module_od import object_index

# Module actions with their own widgets here; the rest go to the generated form.
DEDICATED = frozenset({"unplug", "plug", "swap", "module_power", "set_shaft_speed"})
KIND = "fastcat"  # the coupler's kind in app.classroom.roles


def plug_preset(entry: Mapping[str, Any] | None, catalog: Sequence[str]) -> str | None:
    """The Plug type to offer for a rail entry: for an empty slot, the type the model says
    belongs there (flash, else the last scan: ``expected``); None for a taken slot."""
    if not entry or entry.get("type") is not None:
        return None
    expected = entry.get("expected")
    return str(expected) if expected in catalog else None


def encoder_text(entry: Mapping[str, Any]) -> str:
    rows = []
    for k, enc in enumerate(entry.get("encoders") or [], start=1):
        state = "homing" if enc.get("homing") else ("homed" if enc.get("homed") else "not homed")
        faults = ", ".join(enc.get("faults") or []) or "no fault"
        rpm = float(enc.get("rpm", 0.0))
        rows.append(f"<tr><th>enc {k}</th><td>{esc(enc.get('position', 0))} "
                    f"· {rpm:g} rpm · {esc(state)} · {esc(faults)}</td></tr>")
    return f'<table class="fr-kv">{"".join(rows)}</table>' if rows else ""


@dataclass(frozen=True)
class _RailForm:
    """The instructor's rail rows of one connection (or the shared ones); ``module``: its own
    Module picker (with a token), None when the rows act on the shared one (an open rig)."""

    ops: Any
    plug_type: Any
    swap_with: Any
    powered: Synced
    module: Any = None


def _speed_params(action: Action | None) -> tuple[str, str] | None:
    """(encoder param, rpm param) of set_shaft_speed, found by type: int = which, float = rpm."""
    if action is None:
        return None
    ints = [p.name for p in action.params if p.type is int]
    floats = [p.name for p in action.params if p.type is float]
    return (ints[0], floats[0]) if len(ints) == 1 and len(floats) == 1 else None


class ModulePanel:
    def __init__(self, server: viser.ViserServer, runtime: Runtime, sender: CommandSender,
                 device_id: str, actions: Mapping[str, Action],
                 catalog: Sequence[str]) -> None:
        self._runtime = runtime
        self._sender = sender
        self._id = device_id
        self._rail: list[Mapping[str, Any]] = []
        self._catalog = tuple(catalog)
        module_actions = {n: a for n, a in actions.items() if a.module != "none"}
        self._speed = _speed_params(module_actions.get("set_shaft_speed"))
        gui = server.gui

        with gui.add_folder("Modules"):
            self._module = gui.add_dropdown("Module", ("1",), hint="slot number and type")
            # Plugging, swapping and a module's supply are the instructor's (the box follows
            # the module): built per instructor connection with a token, so a trainee's
            # browser never gets them (app/ui/panels/per_client.py; docs/classroom.md).
            self._server = server
            self._rails = instructor_for(server).part(self._rail_form)
        shared = self._rails.each()[0] if instructor_for(server).shared else None
        self.instructor_only = (shared.ops, shared.plug_type, shared.swap_with,
                                shared.powered.handle) if shared else ()

        with gui.add_folder("Encoder (AX2)", visible=False) as self._encoder_folder:
            self._encoder_state = gui.add_html("")
            self._encoder = gui.add_dropdown("Encoder", ("1", "2"))
            self._rpm = gui.add_number("Shaft speed (rpm)", 60.0, step=1.0)
            set_speed = gui.add_button("Set shaft speed", disabled=self._speed is None)
            self._zero = [gui.add_checkbox(f"Zero-cycle command enc {k + 1}", False,
                                           hint=f"0x7600 bit {12 + k}; the rising edge starts "
                                                "the zero cycle")
                          for k in range(2)]

        instructor = instructor_for(server)
        with gui.add_folder("Module I/O", expand_by_default=False):
            extra = {n: a for n, a in module_actions.items() if n not in DEDICATED}
            # With a token the fault actions are the instructor's own form, with its own
            # Module picker (module_faults.py); an open rig keeps the one form.
            faults = {} if instructor.shared else {
                n: a for n, a in extra.items() if makes_faults(KIND, n)}
            self._form = ActionForm(gui, {n: a for n, a in extra.items() if n not in faults},
                                    self._apply_form)
            self._faults = ModuleFaults(instructor, runtime, sender, device_id, faults,
                                        lambda: self._rail) if faults else None
        self._available: list[str] | None = None  # the selected module's actions, when read
        self._available_lock = threading.Lock()

        # The boxes are values of the selected module: every page ends up showing the model's
        # (Synced). A change commands the module selected when it reaches the server.
        self._zero_syncs = [Synced(server, box, sender,
                                   lambda client, on, k=k: self._zero_cycle(client, k, bool(on)))
                            for k, box in enumerate(self._zero)]

        @self._module.on_update
        def _(event: viser.GuiEvent) -> None:
            self._selection_changed()

        @set_speed.on_click
        def _(event: viser.GuiEvent) -> None:
            target = self._target()
            if target is None or self._speed is None:
                return
            which, rpm = self._speed
            self._sender.send(event.client, target, "set_shaft_speed",
                              {which: int(self._encoder.value), rpm: float(self._rpm.value)})

    def _rail_form(self, gui: Any) -> _RailForm:
        if instructor_for(self._server).shared:
            return self._rail_rows(gui, None)
        # With a token the rows get a Module picker of their own, in a folder of their own:
        # on the shared picker the instructor's pick of the module to pull or switch off went
        # to every trainee's page (docs/classroom.md).
        options = tuple(module_options(self._rail)) or ("1",)
        with gui.add_folder("Rail and power"):
            # Starts at the shared pick (public anyway): what the instructor looked at.
            own = gui.add_dropdown("Module", options, hint="the module the rail rows act on",
                                   initial_value=self._module.value
                                   if self._module.value in options else None)
            return self._rail_rows(gui, own)

    def _rail_rows(self, gui: Any, own: Any) -> _RailForm:
        def target() -> str | None:
            return self._target(None if own is None else own.value)

        form = _RailForm(gui.add_button_group("Rail", ("Unplug", "Plug", "Swap")),
                         # A copy built after the pick (a late instructor) starts at the
                         # preset too, not at the catalog's first type.
                         gui.add_dropdown("Plug type", self._catalog,
                                          initial_value=plug_preset(
                                              self._entry(None if own is None else own.value),
                                              self._catalog)),
                         gui.add_dropdown("Swap with", tuple(module_options(self._rail))
                                          or ("1",)),
                         Synced(self._server, gui.add_checkbox("Module powered", True),
                                self._sender, lambda client, on: self._module_power(
                                    client, on, target())),
                         own)
        if own is not None:
            own.on_update(lambda _event: self._preset(form))

        @form.ops.on_click
        async def _(event: viser.GuiEvent) -> None:
            # On viser's loop: the group's value is still the button of this click.
            button = event.target.value
            target_now = target()
            if target_now is None:
                return
            if button == "Unplug":
                self._sender.send(event.client, target_now, "unplug")
            elif button == "Plug":
                self._sender.send(event.client, target_now, "plug",
                                  {"type": form.plug_type.value})
            else:
                other = option_slot(form.swap_with.value)
                self._sender.send(event.client, target_now, "swap", {"other": other})

        return form

    # ---- helpers ------------------------------------------------------------------------
    def _slot(self, option: Any = None) -> int | None:
        """The slot of ``option`` (an instructor's own pick), else of the shared picker's."""
        return option_slot(str(self._module.value if option is None else option))

    def _target(self, option: Any = None) -> str | None:
        slot = self._slot(option)
        return None if slot is None else f"{self._id}/{slot}"

    def _entry(self, option: Any = None) -> Mapping[str, Any] | None:
        slot = self._slot(option)
        return next((e for e in self._rail if e.get("slot") == slot), None)

    def _form_entry(self, form: _RailForm) -> Mapping[str, Any] | None:
        return self._entry(None if form.module is None else form.module.value)

    def _preset(self, form: _RailForm) -> None:
        """Offer the Plug type the model expects in the form's module (an empty slot)."""
        preset = plug_preset(self._form_entry(form), self._catalog)
        if preset is not None:
            form.plug_type.value = preset

    def _apply_form(self, client: viser.ClientHandle | None, action: str,
                    args: dict[str, Any]) -> None:
        target = self._target()
        if target is not None:
            self._sender.send(client, target, action, args)

    def _module_power(self, client: viser.ClientHandle | None, on: Any,
                      target: str | None) -> None:
        if target is not None:
            self._sender.send(client, target, "module_power", {"on": bool(on)})

    def _zero_cycle(self, client: viser.ClientHandle | None, k: int, on: bool) -> None:
        """Set or clear one zero-cycle bit of 0x7600, keeping the other bits (invert flags)."""
        slot = self._slot()
        if slot is None:
            return
        index, bit = object_index(COMMAND_INDEX, slot), CMD_ZERO_CYCLE[k]
        rig = self._runtime.rig

        def read_modify_write() -> int:
            word = int(rig.apply(self._id, "read_object", {"index": index, "sub": 0}))
            word = word | bit if on else word & ~bit
            rig.apply(self._id, "write_object", {"index": index, "sub": 0, "value": word})
            return word

        self._sender.submit(client, f"0x{index:04X} zero-cycle command", read_modify_write)

    def _selection_changed(self) -> None:
        """Show the encoder section only for an AX2; ask the model which module actions the
        selected module takes (its type decides) for the generated form."""
        entry = self._entry()
        self._encoder_folder.visible = bool(entry and entry.get("encoders") is not None)
        # Offered on a selection or rail change only: a type picked afterwards stays.
        for form in self._rails.each():
            if form.module is None:  # an own picker's rows follow their own pick
                self._preset(form)
        slot = self._slot()
        if slot is None or not (entry and entry.get("type")):
            self._set_available([])
            return
        device = self._id

        def read() -> list[str]:
            return list(self._runtime.rig.device(device).rail_module(slot).available_actions())

        self._sender.submit(None, "module actions", read, done=self._set_available)

    def _set_available(self, names: list[str]) -> None:
        with self._available_lock:
            self._available = names

    # ---- per frame ----------------------------------------------------------------------
    def update(self, snap: Mapping[str, Any]) -> None:
        rail = list(snap.get("rail") or [])
        changed = [(e.get("slot"), e.get("type"), e.get("encoders") is not None)
                   for e in rail] != [(e.get("slot"), e.get("type"),
                                       e.get("encoders") is not None) for e in self._rail]
        self._rail = rail
        if self._faults is not None:
            self._faults.update(changed)
        if changed:
            options = module_options(rail)
            set_options(self._module, options)
            for form in self._rails.each():
                set_options(form.swap_with, options)
                if form.module is not None:
                    set_options(form.module, options)
                    self._preset(form)
            self._selection_changed()
        with self._available_lock:
            available, self._available = self._available, None
        if available is not None:
            self._form.restrict(available)
        # The picked module's values: after a selection change the next frame shows the new
        # module's (a Synced at rest shows what it last followed, so only a difference is sent).
        for form in self._rails.each():
            own = self._form_entry(form)
            if own is not None:
                form.powered.follow(bool(own.get("powered", True)))
        entry = self._entry()
        if entry is None:
            return
        if entry.get("encoders") is not None:
            command = int(entry.get("command", 0))  # 0x7600 as the module holds it
            for k, synced in enumerate(self._zero_syncs):
                synced.follow(bool(command & CMD_ZERO_CYCLE[k]))
            html = encoder_text(entry)
            if self._encoder_state.content != html:
                self._encoder_state.content = html
