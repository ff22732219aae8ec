"""The line's controls (control panel, tab "Line"): the master's faults and every slave's.

Master (its ACTIONS, docs/ethercat-master.md): pull / plug cable i, damage it (a share of
its frames spoiled) / repair it, power a slave off / on, clear a slave's ESC error counters,
lose the next N frames, a DC fault (drift, jitter, lost SYNC0) and its clearing, resync and
the target state. Slaves ("Slave actions"): a "Device" picker and, for the picked one, a
"Target" (the device or one of its expansions / modules, ``cpx/2``) and two forms generated
from its own action table, so an action added to a model appears here unchanged: operation
(TRS-CAT set_input, set_output, acknowledge_messages, ...; CPX-E-EC force, set_input, set_dil,
restart, ...) and, in a folder "trscat faults", what can make a fault (``roles.makes_faults``:
inject_fault, link, field_supply, drop_frames, unplug / plug, ...; short_circuit, wire_break,
supply, cable, ...), which a trainee's page does not show. The model refuses what does not
apply to the target, and each form lists only what its Target takes, as the model says
(app/ui/line/target_actions.py). The Device and each Target are each page's own
(ClientPick), and so are the forms (ClientActionForm): each page lists what its own Target
takes, picks an action, fills its parameters, and its Apply acts on its own Target with its
own values. The FastCAT keeps its own tab. Every command goes through ``CommandSender``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import viser

from app.classroom.roles import makes_faults
from app.runtime import Runtime
from app.ui.commands import CommandSender
from app.ui.line.cables import pulled_text
from app.ui.line.rotary_entry import form_actions, model_args
from app.ui.line.target_actions import TargetActions, Watch, picked, targets
from app.ui.panels.action_form import ActionForm
from app.ui.panels.client_action_form import ClientActionForm
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_pick import ClientPick, send_on
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import from_user, set_options
from devices.device import Action

DC_FAULTS = ("drift", "jitter", "sync0_lost")
TARGETS = ("INIT", "PREOP", "SAFEOP", "OP")
# Actions a slave form leaves out: the Objects tab reads and writes objects.
HIDDEN = {"read_object", "write_object"}


def cable_options(master: Mapping[str, Any], order: Sequence[str]) -> list[str]:
    """One entry per cable, marked as the snapshot has it: "(pulled)" by the master's
    ``pull_cable``, "(pulled at trscat OUT)" when a slave's own plug has it out (Pull / Plug
    move the master's cable only: Plug does not bring that one back)."""
    cables = master.get("cables") or [
        {"index": i, "from": order[i - 1] if i else "master", "to": d, "plugged": True}
        for i, d in enumerate(order)]
    return [f"{c.get('index', i)} {c.get('from', '?')} -> {c.get('to', '?')}"
            f"{_pulled(c)}{_damage(c.get('damaged'))}" for i, c in enumerate(cables)]


def _pulled(cable: Mapping[str, Any]) -> str:
    text = pulled_text(cable)
    return f" ({text})" if text else ""


def _damage(percent: Any) -> str:
    return "" if percent is None else f" (damaged {percent} %)"


def slave_options(master: Mapping[str, Any], order: Sequence[str]) -> list[str]:
    # The instructor's controls: the supply is the injected truth, not the master's view
    # ({} for a list every browser gets: no marks).
    powered = (master.get("injected") or {}).get("powered") or []
    out = []
    for i, device in enumerate(order):
        off = " (off)" if i < len(powered) and powered[i] is False else ""
        out.append(f"{i} {device}{off}")
    return out


def leading_int(text: str) -> int:
    return int(str(text).split(" ", 1)[0])


@dataclass(frozen=True)
class _Cables:
    """The instructor's "Cables and power" rows of one connection (or the shared ones)."""

    cable: Any
    plug: Any
    damage: Any
    damage_ops: Any
    slave_power: Any
    power: Any

    @property
    def handles(self) -> list[Any]:
        return [_handle(self.cable), self.plug, _handle(self.damage), self.damage_ops,
                _handle(self.slave_power), self.power]


@dataclass(frozen=True)
class _Frames:
    """The instructor's "Frames and DC" rows of one connection (or the shared ones)."""

    frames: Any
    lose: Any
    dc_fault: Any
    dc_ops: Any

    @property
    def handles(self) -> list[Any]:
        return [_handle(self.frames), self.lose, _handle(self.dc_fault), self.dc_ops]


def _handle(widget: Any) -> Any:
    """The viser handle of a picker or a box (an open rig's ClientPick or ClientForm)."""
    return widget.handle if isinstance(widget, ClientPick | ClientForm) else widget


def typed(box: Any, client_id: int | None) -> Any:
    """What ``client_id``'s page holds in ``box`` (an open rig's ClientForm: its own; an
    instructor's own copy: its value)."""
    return box.value_for(client_id) if isinstance(box, ClientForm) else box.value


class LineControls:
    def __init__(self, server: viser.ViserServer, sender: CommandSender, master_id: str,
                 order: Sequence[str], actions: Mapping[str, Mapping[str, Action]],
                 devices: Mapping[str, Mapping[str, Any]], own_tabs: Sequence[str],
                 kinds: Mapping[str, str], runtime: Runtime) -> None:
        """``devices``: the first snapshot of each device (the Target lists' first entries;
        :meth:`update` keeps them with the rig); ``own_tabs``: devices
        with their own controls (the FastCAT), left out of "Slave actions"; ``kinds``: each
        device's kind (which of its actions can make a fault)."""
        gui = server.gui
        self._order = list(order)
        self.master_id = master_id
        send = sender.send

        def master(action: str, args: dict[str, Any] | None = None) -> Any:
            return lambda event: send(event.client, master_id, action, args or {})

        # What makes a fault, and says which one was made (the cable list marks the pulled
        # ones): built per instructor connection with a token, so a trainee's browser never
        # gets it nor what the instructor picks (app/ui/panels/per_client.py;
        # docs/classroom.md). Resync and the target state stay everyone's.
        self._send, self._master_id = send, master_id
        self._master_state: Mapping[str, Any] = {}
        instructor = instructor_for(server)
        self._server, self._shared = server, instructor.shared
        self._cables = instructor.part(self._cable_form)
        self._frames = instructor.part(self._frames_form)
        with gui.add_folder("Master", expand_by_default=False):
            gui.add_button("Resync").on_click(master("resync"))
            # A trainee's diagnosis (TwinCAT's "Clear CRC"): a master's write of 0x0300-0x0313.
            # Each page's own pick, as the instructor's pickers are (ClientPick)
            self.esc_slave = ClientPick(server, gui.add_dropdown(
                "ESC counters of", tuple(slave_options({}, order)) or ("-",)))
            clear_esc = gui.add_button("Clear ESC error counters")
            self.target = gui.add_dropdown("Target state", TARGETS, initial_value="OP")
        self._esc_marks = instructor.shared
        cables = self._cables.each()[0] if instructor.shared else None
        frames = self._frames.each()[0] if instructor.shared else None
        # Open rig: the server-level widgets, as before (tests, Dashboard.instructor_widgets).
        self.cable = cables.cable if cables else None
        self.damage = _handle(cables.damage) if cables else None
        self.slave_power = cables.slave_power if cables else None
        self.frames = _handle(frames.frames) if frames else None
        self.dc_fault = frames.dc_fault if frames else None
        self.instructor_only: list[Any] = [*cables.handles, *frames.handles] \
            if cables and frames else []
        self.forms: dict[str, tuple[Any, ClientActionForm]] = {}
        self.fault_forms: dict[str, ClientActionForm] = {}
        self.targets: dict[str, ClientPick] = {}  # each slave's Target picker (tests)
        self._target_actions = TargetActions(runtime, sender)
        self._watches: list[Watch] = []  # the shared Targets' (an instructor's: _Injure)
        # Each device's latest snapshot: a form starts from the present values (Param.current).
        self._snapshots: dict[str, Mapping[str, Any]] = dict(devices)
        faulty = [d for d in order if d not in own_tabs]
        fault_tables: dict[str, Mapping[str, Action]] = {}
        with gui.add_folder("Slave actions"):
            # Each page's own (client_pick): one page's pick of the slave to operate, or its
            # click in the 3D view, moved every page's form.
            self.pick = ClientPick(server, gui.add_dropdown("Device", tuple(faulty) or ("-",)))
            for device in faulty:
                kind = kinds.get(device, "")
                # The CPX-E-EC's rotary value typed in hex, as seed 002 Tab. 5 writes it.
                shown = form_actions(kind, {n: a for n, a in (actions.get(device) or {}).items()
                                            if n not in HIDDEN})
                faults = {n: a for n, a in shown.items() if makes_faults(kind, n)}
                folder = gui.add_folder(device, visible=device == self.pick.default)
                with folder:
                    # Each page's own, as the Device: one page's pick of a module moved what
                    # every page's forms acted on.
                    target = ClientPick(server, gui.add_dropdown(
                        "Target", tuple(targets(device, devices.get(device) or {}))))
                    self.targets[device] = target
                    apply = self._applier(sender, target, kind=kind)
                    # Each page's own (client_action_form): one form for every page switched
                    # every page's pick and sent one page's values with another's Apply.
                    form = ClientActionForm(
                        server, {n: a for n, a in shown.items() if n not in faults}, apply,
                        current=self._current(device))
                    if instructor.shared:  # an open rig: under the shared Target, as before
                        part = instructor.part(self._fault_folder(
                            server, device, faults, self._applier(sender, target, confirm=True)))
                        self.fault_forms[device] = part.each()[0]
                        self.instructor_only += self.fault_forms[device].handles
                    else:
                        fault_tables[device] = faults
                    shared = [form, *([self.fault_forms[device]]
                                      if device in self.fault_forms else [])]
                    self._watches.append(self._target_actions.watch(
                        device, target, shared, self._picks(server, target)))
                self.forms[device] = (folder, form)
        # With a token the fault forms are the instructor's whole, with a Device and a Target
        # picker of their own: picking the slave to injure in the shared ones moved every
        # trainee's page (docs/classroom.md).
        self._injure = None if instructor.shared else instructor.part(
            lambda gui: self._injure_form(gui, sender, fault_tables, devices))

        @clear_esc.on_click
        def _(event: viser.GuiEvent) -> None:
            send(event.client, master_id, "clear_esc_errors",
                 {"position": leading_int(self.esc_slave.value_for(event.client_id))})

        @self.target.on_update
        def _(event: viser.GuiEvent) -> None:
            if from_user(event):
                send(event.client, master_id, "set_target", {"state": self.target.value})

        self.pick.on_pick(lambda client, device: self._show(device, client))

    def _own(self, handle: Any) -> Any:
        """An open rig's picker is each page's own (ClientPick): one operator's pick of the
        cable to pull or the slave to switch off moved every other page's, and what its
        buttons then sent. An instructor's copy is its connection's anyway."""
        return ClientPick(self._server, handle) if self._shared else handle

    def _own_box(self, handle: Any) -> Any:
        """An open rig's box is each page's own (ClientForm): one operator's Spoiled % or
        Frames to lose showed in every page's box and went with another page's click."""
        return ClientForm(self._server, handle) if self._shared else handle

    def _cable_form(self, gui: Any) -> _Cables:
        send, master_id, order = self._send, self._master_id, self._order
        with gui.add_folder("Cables and power"):
            form = _Cables(
                self._own(gui.add_dropdown("Cable", tuple(cable_options(
                    self._master_state, order)) or ("-",))),
                gui.add_button_group("Cable plug", ("Pull", "Plug")),
                self._own_box(gui.add_number("Spoiled %", 10, min=1, max=100, step=1,
                                             hint="share of the frames the cable spoils")),
                gui.add_button_group("Cable damage", ("Damage", "Repair")),
                self._own(gui.add_dropdown("Slave to power", tuple(slave_options(
                    self._master_state, order)) or ("-",))),
                gui.add_button_group("Slave power", ("Power off", "Power on")))

        # On viser's loop (coroutines): a group's value is still the button of this click.
        @form.plug.on_click
        async def _(event: viser.GuiEvent) -> None:
            verb = "pull_cable" if event.target.value == "Pull" else "plug_cable"
            send(event.client, master_id, verb,
                 {"cable": leading_int(picked(form.cable, event.client_id))})

        @form.damage_ops.on_click
        async def _(event: viser.GuiEvent) -> None:
            cable = leading_int(picked(form.cable, event.client_id))
            if event.target.value == "Damage":
                send(event.client, master_id, "damage_cable",
                     {"cable": cable, "percent": int(typed(form.damage, event.client_id))})
            else:
                send(event.client, master_id, "repair_cable", {"cable": cable})

        @form.power.on_click
        async def _(event: viser.GuiEvent) -> None:
            send(event.client, master_id, "power_slave",
                 {"position": leading_int(picked(form.slave_power, event.client_id)),
                  "on": event.target.value == "Power on"})

        return form

    def _frames_form(self, gui: Any) -> _Frames:
        send, master_id = self._send, self._master_id
        with gui.add_folder("Frames and DC"):
            form = _Frames(self._own_box(gui.add_number("Frames to lose", 10, min=1,
                                                        max=100000, step=1)),
                           gui.add_button("Lose frames"),
                           self._own(gui.add_dropdown("DC fault", DC_FAULTS)),
                           gui.add_button_group("DC", ("Inject", "Clear")))

        @form.lose.on_click
        def _(event: viser.GuiEvent) -> None:
            send(event.client, master_id, "lose_frames",
                 {"count": int(typed(form.frames, event.client_id))})

        @form.dc_ops.on_click
        async def _(event: viser.GuiEvent) -> None:
            if event.target.value == "Inject":
                send(event.client, master_id, "dc_fault",
                     {"kind": picked(form.dc_fault, event.client_id)})
            else:
                send(event.client, master_id, "clear_dc_fault", {})

        return form

    @staticmethod
    def _fault_folder(server: viser.ViserServer, device: str, faults: Mapping[str, Action],
                      apply: Any) -> Any:
        """An open rig's fault form of the slave, in a closed folder of its own: each page's
        own, as the operation form."""
        def build(gui: Any) -> ClientActionForm:
            with gui.add_folder(f"{device} faults", expand_by_default=False):
                return ClientActionForm(server, faults, apply, label="Fault action")
        return build

    def _injure_form(self, gui: Any, sender: CommandSender,
                     tables: Mapping[str, Mapping[str, Action]],
                     devices: Mapping[str, Mapping[str, Any]]) -> list[Watch]:
        """One instructor connection's "Slave faults": its Device picker, and per slave a
        Target picker and the fault form acting on it (each a Watch: what its Target takes)."""
        folders: dict[str, Any] = {}
        watches: list[Watch] = []
        with gui.add_folder("Slave faults", expand_by_default=False):
            picker = gui.add_dropdown("Device", tuple(tables) or ("-",))
            for device, faults in tables.items():
                folders[device] = gui.add_folder(device, visible=device == picker.value)
                with folders[device]:
                    target = gui.add_dropdown("Target", tuple(targets(
                        device, self._snapshots.get(device) or devices.get(device) or {})))
                    form = ActionForm(gui, faults, self._applier(sender, target, confirm=True),
                                      label="Fault action")
                    watches.append(self._target_actions.watch(device, target, [form]))

        @picker.on_update
        def _(event: viser.GuiEvent) -> None:
            for name, folder in folders.items():
                folder.visible = name == picker.value

        return watches

    def _current(self, device: str) -> Any:
        return lambda: self._snapshots.get(device)

    @staticmethod
    def _picks(server: viser.ViserServer, target: ClientPick) -> Any:
        """Every page's pick of ``target``, and a new page's."""
        return lambda: {target.value_for(c) for c in server.get_clients()} | {target.default}

    @staticmethod
    def _applier(sender: CommandSender, target: Any, confirm: bool = False,
                 kind: str = "") -> Any:
        """``confirm``: a fault form's, whose Apply is confirmed on the clicking page; the
        target is the clicking page's pick; ``kind``: the device's, whose form may take a
        value as its manual writes it (rotary_entry)."""
        def apply(client: viser.ClientHandle | None, name: str, args: dict[str, Any]) -> None:
            where = picked(target, None if client is None else client.client_id)
            sender.send(client, where, name, model_args(kind, name, args), confirm=confirm)
        return apply

    def all_forms(self) -> dict[str, list[ClientActionForm]]:
        """Every server-level slave form, per device: operation, then faults (open rig;
        with a token the fault forms are the instructor connections') (tests)."""
        return {d: [form, *([self.fault_forms[d]] if d in self.fault_forms else [])]
                for d, (_folder, form) in self.forms.items()}

    @property
    def selected(self) -> str:
        """The slave a new page starts at (the last pick for every page)."""
        return self.pick.default

    def selected_for(self, client_id: int | None) -> str:
        return self.pick.value_for(client_id)

    def select(self, device: str, client: viser.ClientHandle | None = None) -> None:
        """Show the forms of ``device`` on ``client``'s page (a click on it in the 3D view),
        on every page when None (a scenario's focus)."""
        if device not in self.forms:
            return
        self.pick.pick(device, client)
        self._show(device, client)

    def _show(self, device: str, client: viser.ClientHandle | None) -> None:
        """The picked slave's folder, the others' hidden: on ``client``'s page, or on every
        page (a page's own visibility goes to it alone, as its pick does)."""
        for name, (folder, _form) in self.forms.items():
            send_on(client, folder, "visible", name == device)

    def update(self, master: Mapping[str, Any],
               devices: Mapping[str, Mapping[str, Any]] | None = None) -> None:
        if devices is not None:
            self._snapshots = dict(devices)  # replaced whole: read from callback threads
        own = [w for watches in (self._injure.each() if self._injure else []) for w in watches]
        self._target_actions.update([*self._watches, *own], devices)
        self._master_state = master
        cables, slaves = cable_options(master, self._order), slave_options(master, self._order)
        for form in self._cables.each():
            for widget, options in ((form.cable, cables), (form.slave_power, slaves)):
                if isinstance(widget, ClientPick):  # each page's pick keeps its cable / slave
                    widget.set_options(options)
                else:
                    set_options(widget, options)
        # Everyone's list: the "(off)" marks are the injected supply, which a real master
        # cannot read (a slave off looks like its cable pulled): with a token only on the
        # instructor's own Slave to power list (docs/classroom.md).
        self.esc_slave.set_options(slave_options(master if self._esc_marks else {},
                                                 self._order))
