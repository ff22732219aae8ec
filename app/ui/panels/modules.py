"""Module controls: pick a slot, unplug / plug / swap it, power it, drive its I/O and encoders.

What an operator does to the rail with their hands (seed 000 §2: modules can be plugged,
unplugged and swapped; the coupler notices at the next scan or, in OP, at once) goes through
the FastCAT's module actions on the target ``<device>/<slot>``. AX2 modules get an encoder
section: shaft speed per encoder and the zero-cycle command bits of 0x7600 (§6.30, bits 12 /
13), written with ``write_object`` like a PLC would write its output.

The Module picker is each page's own (a ClientPick), and so is what follows its pick: the
encoder section and its boxes (Encoder and Shaft speed: ClientForms), the open rig's Rail
rows (Plug type preset, Swap with, Module powered) and the module Module I/O and the buttons
act on, the clicking page's, and the Module I/O form itself: the actions its module takes, the
one it picked and its parameters (a ClientActionForm; docs/dashboard.md "Several browsers").
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import viser

from app.classroom.roles import makes_faults
from app.runtime import Runtime
from app.ui.commands import CommandSender
from app.ui.panels.client_action_form import ClientActionForm
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_input import ClientSynced
from app.ui.panels.client_pick import ClientHtml, ClientPick, page_ready
from app.ui.panels.control import module_options, option_slot
from app.ui.panels.module_faults import ModuleFaults
from app.ui.panels.page_prop import PageProp
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import Synced, set_options
from app.ui.style import esc
from devices.device import Action, CommandError
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


def command_index(entry: Mapping[str, Any]) -> int:
    """The index of the AX2's 0x7600 in a rail entry: 0x7600 + 0x10 * (N - 1) with N the
    module number the last scan gave it (seed 000 §6.30, §6.24: the modules detected along
    the bus), not its slot, which differs behind an empty slot. A module the last scan did
    not number has no object to write."""
    number = entry.get("module_number")
    if number is None:
        raise CommandError(f"slot {entry.get('slot')}: the last scan did not number this "
                           "module, so it has no 0x7600 yet (the coupler numbers the modules "
                           "at a scan: CNF or a return to INIT)")
    return object_index(COMMAND_INDEX, int(number))


@dataclass
class _RailForm:
    """The rail rows of one instructor connection, or the shared ones of an open rig.
    ``module``: the connection's own Module picker (with a token); None for the shared rows,
    which act on each page's pick of the Module picker, with a Plug type and a Swap with of
    each page's own (ClientPick) and a Module powered box per page (ClientSynced).

    ``lock``: held while a Plug type preset reads the pick and the rail and writes the type.
    Its writers are a Module pick (viser's threads) and a rail change's frame update: the
    update that read the pick before the page picked another empty slot wrote the old slot's
    type over the pick's, and no frame presets again before the next rail change. Reentrant:
    assigning a widget runs its callbacks at once in the assigning thread (viser 1.1.1)."""

    ops: Any
    plug_type: Any
    swap_with: Any
    powered: Synced | ClientSynced
    module: Any = None
    lock: Any = field(default_factory=threading.RLock)


def _value(widget: Any, client_id: int | None) -> str:
    """What ``widget`` holds on ``client_id``'s page (a ClientPick: the page's own)."""
    return widget.value_for(client_id) if isinstance(widget, ClientPick) else str(widget.value)


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
        self._server = server
        self._id = device_id
        self._rail: list[Mapping[str, Any]] = []
        self._catalog = tuple(catalog)
        module_actions = {n: a for n, a in actions.items() if a.module != "none"}
        self._speed = _speed_params(module_actions.get("set_shaft_speed"))
        gui = server.gui

        with gui.add_folder("Modules"):
            # Each page's own (client_pick): one trainee's pick of module 3 moved every other
            # page's picker and what its Rail buttons and Module I/O acted on.
            self.pick = ClientPick(server, gui.add_dropdown("Module", ("1",),
                                                            hint="slot number and type"))
            # Plugging, swapping and a module's supply are the instructor's (the box follows
            # the module): built per instructor connection with a token, so a trainee's
            # browser never gets them (app/ui/panels/per_client.py; docs/classroom.md).
            self._rails = instructor_for(server).part(self._rail_form)
        shared = self._rails.each()[0] if instructor_for(server).shared else None
        self._shared_rail = shared
        self.instructor_only = (shared.ops, shared.plug_type.handle, shared.swap_with.handle,
                                shared.powered.handle) if shared else ()
        self._preset_pages: set[int] = set()  # the pages whose Plug type got their preset

        with gui.add_folder("Encoder (AX2)", visible=False) as encoder_folder:
            self._encoder_state = ClientHtml(server, gui.add_html(""))
            # Each page's own boxes, as the section is: typed on one page, they were every
            # page's, and a classmate's Set shaft speed sent them.
            self._encoder = ClientForm(server, gui.add_dropdown("Encoder", ("1", "2")))
            self._rpm = ClientForm(server, gui.add_number("Shaft speed (rpm)", 60.0, step=1.0))
            set_speed = gui.add_button("Set shaft speed", disabled=self._speed is None)
            self._zero = [gui.add_checkbox(f"Zero-cycle command enc {k + 1}", False,
                                           hint=f"0x7600 bit {12 + k}; the rising edge starts "
                                                "the zero cycle")
                          for k in range(2)]
        self._encoder_shown = PageProp(server, encoder_folder, "visible")

        instructor = instructor_for(server)
        with gui.add_folder("Module I/O", expand_by_default=False):
            extra = {n: a for n, a in module_actions.items() if n not in DEDICATED}
            # With a token the fault actions are the instructor's own form, with its own
            # Module picker (module_faults.py); an open rig keeps the one form.
            faults = {} if instructor.shared else {
                n: a for n, a in extra.items() if makes_faults(KIND, n)}
            # Each page's own: one form for every page switched every page's pick and sent
            # what one page typed with another page's Apply.
            self._form = ClientActionForm(
                server, {n: a for n, a in extra.items() if n not in faults}, self._apply_form)
            self._faults = ModuleFaults(instructor, runtime, sender, device_id, faults,
                                        lambda: self._rail) if faults else None
        # What each picked slot's module takes, read from the model for the rail as it is
        # (``_rail_key``): the form offers each page what its own pick takes.
        self._actions_lock = threading.Lock()
        self._actions_of: dict[int, list[str]] = {}
        self._asked: set[int] = set()
        self._rail_key = 0

        # The boxes are values of each page's module: every page ends up showing the model's
        # (ClientSynced). A change commands the module its page picked.
        self._zero_syncs = [ClientSynced(server, box, sender,
                                         lambda client, on, k=k: self._zero_cycle(
                                             client, k, bool(on)))
                            for k, box in enumerate(self._zero)]

        self.pick.on_pick(lambda client, _option: self._page_picked(client))

        @set_speed.on_click
        def _(event: viser.GuiEvent) -> None:
            target = self._target(self.pick.value_for(event.client_id))
            if target is None or self._speed is None:
                return
            which, rpm = self._speed
            self._sender.send(event.client, target, "set_shaft_speed",
                              {which: int(self._encoder.value_of(event.client)),
                               rpm: float(self._rpm.value_of(event.client))})

    def _rail_form(self, gui: Any) -> _RailForm:
        if instructor_for(self._server).shared:
            return self._rail_rows(gui, None)
        # With a token the rows get a Module picker of their own, in a folder of their own:
        # on the shared picker the instructor's pick of the module to pull or switch off went
        # to every trainee's page (docs/classroom.md).
        options = self._options()
        with gui.add_folder("Rail and power"):
            # Starts where a new page's Module picker does (public anyway).
            start = self.pick.default
            own = gui.add_dropdown("Module", options, hint="the module the rail rows act on",
                                   initial_value=start if start in options else None)
            return self._rail_rows(gui, own)

    def _rail_rows(self, gui: Any, own: Any) -> _RailForm:
        def target(client_id: int | None) -> str | None:
            return self._target(self.pick.value_for(client_id) if own is None else own.value)

        ops = gui.add_button_group("Rail", ("Unplug", "Plug", "Swap"))
        # A copy built after the pick (a late instructor) starts at the preset too, not at
        # the catalog's first type.
        plug_type = gui.add_dropdown("Plug type", self._catalog, initial_value=None
                                     if own is None else plug_preset(self._entry(own.value),
                                                                     self._catalog))
        swap_with = gui.add_dropdown("Swap with", self._options())
        powered = gui.add_checkbox("Module powered", True)
        if own is None:  # the shared rows: each page's own pick
            form = _RailForm(ops, ClientPick(self._server, plug_type),
                             ClientPick(self._server, swap_with),
                             ClientSynced(self._server, powered, self._sender,
                                          lambda client, on: self._module_power(
                                              client, on, target(_id(client)))))
        else:
            form = _RailForm(ops, plug_type, swap_with,
                             Synced(self._server, powered, self._sender,
                                    lambda client, on: self._module_power(
                                        client, on, target(None))), own)
            own.on_update(lambda _event: self._preset(form))

        @form.ops.on_click
        async def _(event: viser.GuiEvent) -> None:
            # On viser's loop: the group's value is still the button of this click.
            button = event.target.value
            target_now = target(event.client_id)
            if target_now is None:
                return
            if button == "Unplug":
                self._sender.send(event.client, target_now, "unplug")
            elif button == "Plug":
                self._sender.send(event.client, target_now, "plug",
                                  {"type": _value(form.plug_type, event.client_id)})
            else:
                other = option_slot(_value(form.swap_with, event.client_id))
                self._sender.send(event.client, target_now, "swap", {"other": other})

        return form

    # ---- helpers ------------------------------------------------------------------------
    def _options(self) -> tuple[str, ...]:
        """An own Module / Swap with picker's options: the rail's ("1" before there is one)."""
        return tuple(module_options(self._rail)) or ("1",)

    def _target(self, option: Any) -> str | None:
        slot = option_slot(str(option))
        return None if slot is None else f"{self._id}/{slot}"

    def _entry(self, option: Any) -> Mapping[str, Any] | None:
        slot = option_slot(str(option))
        return next((e for e in self._rail if e.get("slot") == slot), None)

    def _entry_for(self, client_id: int | None) -> Mapping[str, Any] | None:
        """The rail entry of ``client_id``'s pick (None: a new page's)."""
        return self._entry(self.pick.value_for(client_id))

    def _preset(self, form: _RailForm) -> None:
        """Offer the Plug type the model expects in an own picker's module (an empty slot)."""
        with form.lock:
            preset = plug_preset(self._entry(form.module.value), self._catalog)
            if preset is not None:
                form.plug_type.value = preset

    def _preset_page(self, client: viser.ClientHandle) -> None:
        """The shared rows' Plug type on ``client``'s page: the type its empty slot expects."""
        shared = self._shared_rail
        if shared is None:
            return
        with shared.lock:
            preset = plug_preset(self._entry_for(client.client_id), self._catalog)
            if preset is not None:
                shared.plug_type.set_for(client, preset)

    def _apply_form(self, client: viser.ClientHandle | None, action: str,
                    args: dict[str, Any]) -> None:
        target = self._target(self.pick.value_for(_id(client)))
        if target is not None:
            self._sender.send(client, target, action, args)

    def _module_power(self, client: viser.ClientHandle | None, on: Any,
                      target: str | None) -> None:
        if target is not None:
            self._sender.send(client, target, "module_power", {"on": bool(on)})

    def _zero_cycle(self, client: viser.ClientHandle | None, k: int, on: bool) -> None:
        """Set or clear one zero-cycle bit of 0x7600, keeping the other bits (invert flags)."""
        slot = option_slot(self.pick.value_for(_id(client)))
        if slot is None:
            return
        bit = CMD_ZERO_CYCLE[k]
        rig = self._runtime.rig

        def read_modify_write() -> int:
            # The module number as the coupler has it now: the click may follow a rescan.
            entry = rig.device(self._id).snapshot()["rail"][slot - 1]
            index = command_index(entry)
            word = int(rig.apply(self._id, "read_object", {"index": index, "sub": 0}))
            word = word | bit if on else word & ~bit
            rig.apply(self._id, "write_object", {"index": index, "sub": 0, "value": word})
            return word

        self._sender.submit(client, f"slot {slot} 0x7600 zero-cycle command", read_modify_write)

    def _page_picked(self, client: viser.ClientHandle) -> None:
        """A page picked a module: its Plug type preset, its encoder section, the actions."""
        self._preset_page(client)
        self._show_pages()
        self._ask_actions()

    def _show_pages(self) -> None:
        """The encoder section on the pages whose pick is an AX2, with its encoders."""
        def encoders(client_id: int) -> bool:
            entry = self._entry_for(client_id)
            return bool(entry and entry.get("encoders") is not None)

        self._encoder_shown.show(encoders)
        self._encoder_state.show(lambda client_id: encoder_text(self._entry_for(client_id) or {})
                                 if encoders(client_id) else "")

    def _picked_slots(self) -> set[int]:
        picks = {self.pick.value_for(c) for c in self._server.get_clients()}
        return {s for s in (option_slot(p) for p in picks | {self.pick.default})
                if s is not None}

    def _ask_actions(self) -> None:
        """Ask the model which actions the picked modules take (their types decide), for
        the slots not asked about on this rail yet."""
        with self._actions_lock:
            key = self._rail_key
            slots = self._picked_slots() - self._asked
            self._asked |= slots
        device = self._id
        for slot in slots:
            entry = self._entry(slot)
            if not (entry and entry.get("type")):
                self._park(key, slot, [])
                continue

            def read(slot: int = slot) -> list[str]:
                module = self._runtime.rig.device(device).rail_module(slot)
                return list(module.available_actions())

            self._sender.submit(None, "module actions", read,
                                done=lambda names, slot=slot: self._park(key, slot, names))

    def _park(self, key: int, slot: int, names: list[str]) -> None:
        with self._actions_lock:
            if key == self._rail_key:  # else an answer about the rail as it was
                self._actions_of[slot] = names

    def _offer(self) -> None:
        """Module I/O offers each page what its picked module takes, once known."""
        self._ask_actions()
        with self._actions_lock:
            known = dict(self._actions_of)

        def names(client_id: int | None) -> list[str] | None:
            slot = option_slot(self.pick.value_for(client_id))
            return [] if slot is None else known.get(slot)

        self._form.restrict_each(names)

    # ---- per frame ----------------------------------------------------------------------
    def update(self, snap: Mapping[str, Any]) -> None:
        rail = list(snap.get("rail") or [])
        changed = [(e.get("slot"), e.get("type"), e.get("encoders") is not None)
                   for e in rail] != [(e.get("slot"), e.get("type"),
                                       e.get("encoders") is not None) for e in self._rail]
        # The Plug type presets again when what they read changes, an empty slot's
        # ``expected`` too: a CNF (flash) or a scan (the last scan) changes it, not the rail,
        # and the box kept offering the old expected module until an unrelated rail change.
        represet = changed or _preset_key(rail) != _preset_key(self._rail)
        self._rail = rail
        if self._faults is not None:
            self._faults.update(changed)
        if changed:
            options = module_options(rail)
            self.pick.set_options(options)
            with self._actions_lock:
                self._rail_key += 1
                self._actions_of.clear()
                self._asked.clear()
            for form in self._rails.each():
                if form.module is None:
                    form.swap_with.set_options(options)
        if represet:
            self._preset_pages.clear()  # offered on such a change: a type picked later stays
        # An instructor's own rows: every copy whose options are not the rail's, not only on
        # the frame the rail changed (a copy built from the rail before that frame and stored
        # after it, by a promote on another thread, kept the old options for good).
        own = list(self._options())
        for form in self._rails.each():
            if form.module is None:
                continue
            moved = changed or list(form.module.options) != own \
                or list(form.swap_with.options) != own
            if moved:
                set_options(form.swap_with, own)
                set_options(form.module, own)
            if moved or represet:
                self._preset(form)
        self._offer()
        self._show_pages()
        shared = self._shared_rail
        if shared is not None:
            self._preset_new_pages(shared)

            def powered(client_id: int) -> bool | None:
                entry = self._entry_for(client_id)
                return None if entry is None else bool(entry.get("powered", True))

            shared.powered.follow_each(powered)
        # The picked module's values: after a selection change the next frame shows the new
        # module's (a Synced at rest shows what it last followed, so only a difference is sent).
        for form in self._rails.each():
            if form.module is not None and (own := self._entry(form.module.value)) is not None:
                form.powered.follow(bool(own.get("powered", True)))
        for k, synced in enumerate(self._zero_syncs):
            synced.follow_each(lambda client_id, k=k: self._zero_bit(client_id, k))

    def _zero_bit(self, client_id: int, k: int) -> bool | None:
        """Zero-cycle bit ``k`` of 0x7600 as the page's AX2 holds it (None: no AX2)."""
        entry = self._entry_for(client_id)
        if entry is None or entry.get("encoders") is None:
            return None
        return bool(int(entry.get("command", 0)) & CMD_ZERO_CYCLE[k])

    def _preset_new_pages(self, shared: _RailForm) -> None:
        """A page new to the shared rows (or every page after a rail change) gets the Plug
        type its pick's empty slot expects, once it has the box (page_ready)."""
        for client_id, client in self._server.get_clients().items():
            if client_id in self._preset_pages or not page_ready(self._server, client):
                continue
            self._preset_pages.add(client_id)
            self._preset_page(client)
        self._preset_pages &= set(self._server.get_clients())


def _preset_key(rail: Sequence[Mapping[str, Any]]) -> list[tuple[Any, Any, Any]]:
    """What the Plug type presets read of the rail (``plug_preset``): each slot's type and,
    for an empty one, the type it expects."""
    return [(e.get("slot"), e.get("type"), e.get("expected")) for e in rail]


def _id(client: viser.ClientHandle | None) -> int | None:
    return None if client is None else client.client_id
