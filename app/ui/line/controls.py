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
apply to the target. The FastCAT keeps its own tab. Every command goes through
``CommandSender``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import viser

from app.classroom.roles import makes_faults
from app.ui.commands import CommandSender
from app.ui.line.cables import pulled_text
from app.ui.panels.action_form import ActionForm
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
    slaves = master.get("slaves") or []
    out = []
    for i, device in enumerate(order):
        entry = slaves[i] if i < len(slaves) else {}
        off = " (off)" if entry.get("powered") is False else ""
        out.append(f"{i} {device}{off}")
    return out


def targets(device: str, snap: Mapping[str, Any]) -> list[str]:
    """The device and its parts a command can address: TRS-CAT expansions (slots 1..),
    CPX-E-EC modules (1..)."""
    parts = [int(s.get("slot", 0)) for s in snap.get("slots") or []][1:]
    parts += [int(m.get("module", 0)) for m in snap.get("modules") or []]
    return [device, *(f"{device}/{n}" for n in parts)]


def leading_int(text: str) -> int:
    return int(str(text).split(" ", 1)[0])


class LineControls:
    def __init__(self, server: viser.ViserServer, sender: CommandSender, master_id: str,
                 order: Sequence[str], actions: Mapping[str, Mapping[str, Action]],
                 devices: Mapping[str, Mapping[str, Any]], own_tabs: Sequence[str],
                 kinds: Mapping[str, str]) -> None:
        """``devices``: the first snapshot of each device (its parts); ``own_tabs``: devices
        with their own controls (the FastCAT), left out of "Slave actions"; ``kinds``: each
        device's kind (which of its actions can make a fault)."""
        gui = server.gui
        self._order = list(order)
        self.master_id = master_id
        send = sender.send

        def master(action: str, args: dict[str, Any] | None = None) -> Any:
            return lambda event: send(event.client, master_id, action, args or {})

        with gui.add_folder("Cables and power"):
            self.cable = gui.add_dropdown("Cable", tuple(cable_options({}, order)) or ("-",))
            cable_buttons = gui.add_button_group("Cable plug", ("Pull", "Plug"))
            self.damage = gui.add_number("Spoiled %", 10, min=1, max=100, step=1,
                                         hint="share of the frames the cable spoils")
            damage_buttons = gui.add_button_group("Cable damage", ("Damage", "Repair"))
            self.slave_power = gui.add_dropdown("Slave to power", tuple(slave_options({}, order))
                                                or ("-",))
            power_buttons = gui.add_button_group("Slave power", ("Power off", "Power on"))
        with gui.add_folder("Frames and DC"):
            self.frames = gui.add_number("Frames to lose", 10, min=1, max=100000, step=1)
            lose = gui.add_button("Lose frames")
            self.dc_fault = gui.add_dropdown("DC fault", DC_FAULTS)
            dc_buttons = gui.add_button_group("DC", ("Inject", "Clear"))
        with gui.add_folder("Master", expand_by_default=False):
            gui.add_button("Resync").on_click(master("resync"))
            # A trainee's diagnosis (TwinCAT's "Clear CRC"): a master's write of 0x0300-0x0313.
            self.esc_slave = gui.add_dropdown("ESC counters of",
                                              tuple(slave_options({}, order)) or ("-",))
            clear_esc = gui.add_button("Clear ESC error counters")
            self.target = gui.add_dropdown("Target state", TARGETS, initial_value="OP")
        # What makes a fault, and says which one was made: not on a trainee's page (the
        # classroom's trainee CSS; docs/classroom.md). Resync and the target state stay.
        self.instructor_only = [self.cable, cable_buttons, self.damage, damage_buttons,
                                self.slave_power, power_buttons, self.frames, lose,
                                self.dc_fault, dc_buttons]
        self.forms: dict[str, tuple[Any, ActionForm]] = {}
        self.fault_forms: dict[str, ActionForm] = {}
        # Each device's latest snapshot: a form starts from the present values (Param.current).
        self._snapshots: dict[str, Mapping[str, Any]] = dict(devices)
        faulty = [d for d in order if d not in own_tabs]
        with gui.add_folder("Slave actions"):
            self.picker = gui.add_dropdown("Device", tuple(faulty) or ("-",))
            for device in faulty:
                shown = {n: a for n, a in (actions.get(device) or {}).items()
                         if n not in HIDDEN}
                kind = kinds.get(device, "")
                faults = {n: a for n, a in shown.items() if makes_faults(kind, n)}
                folder = gui.add_folder(device, visible=device == self.picker.value)
                with folder:
                    target = gui.add_dropdown("Target", tuple(targets(device,
                                                                      devices.get(device) or {})))
                    apply = self._applier(sender, target)
                    form = ActionForm(gui, {n: a for n, a in shown.items() if n not in faults},
                                      apply, current=self._current(device))
                    # The instructor's: its folder goes from a trainee's page as a whole
                    # (rebuilt parameter rows and all; docs/classroom.md).
                    with gui.add_folder(f"{device} faults", expand_by_default=False):
                        fault_form = ActionForm(gui, faults, apply, label="Fault action")
                self.forms[device] = (folder, form)
                self.fault_forms[device] = fault_form
                self.instructor_only += fault_form.handles

        @cable_buttons.on_click
        def _(event: viser.GuiEvent) -> None:
            verb = "pull_cable" if cable_buttons.value == "Pull" else "plug_cable"
            send(event.client, master_id, verb, {"cable": leading_int(self.cable.value)})

        @damage_buttons.on_click
        def _(event: viser.GuiEvent) -> None:
            cable = leading_int(self.cable.value)
            if damage_buttons.value == "Damage":
                send(event.client, master_id, "damage_cable",
                     {"cable": cable, "percent": int(self.damage.value)})
            else:
                send(event.client, master_id, "repair_cable", {"cable": cable})

        @clear_esc.on_click
        def _(event: viser.GuiEvent) -> None:
            send(event.client, master_id, "clear_esc_errors",
                 {"position": leading_int(self.esc_slave.value)})

        @power_buttons.on_click
        def _(event: viser.GuiEvent) -> None:
            send(event.client, master_id, "power_slave",
                 {"position": leading_int(self.slave_power.value),
                  "on": power_buttons.value == "Power on"})

        @lose.on_click
        def _(event: viser.GuiEvent) -> None:
            send(event.client, master_id, "lose_frames", {"count": int(self.frames.value)})

        @dc_buttons.on_click
        def _(event: viser.GuiEvent) -> None:
            if dc_buttons.value == "Inject":
                send(event.client, master_id, "dc_fault", {"kind": self.dc_fault.value})
            else:
                send(event.client, master_id, "clear_dc_fault", {})

        @self.target.on_update
        def _(event: viser.GuiEvent) -> None:
            if from_user(event):
                send(event.client, master_id, "set_target", {"state": self.target.value})

        @self.picker.on_update
        def _(event: viser.GuiEvent) -> None:
            self.select(self.picker.value)

    def _current(self, device: str) -> Any:
        return lambda: self._snapshots.get(device)

    @staticmethod
    def _applier(sender: CommandSender, target: Any) -> Any:
        def apply(client: viser.ClientHandle | None, name: str, args: dict[str, Any]) -> None:
            sender.send(client, str(target.value), name, args)
        return apply

    def all_forms(self) -> dict[str, list[ActionForm]]:
        """Every slave form, per device: operation, then faults (tests)."""
        return {d: [form, self.fault_forms[d]] for d, (_folder, form) in self.forms.items()}

    def select(self, device: str) -> None:
        """Show the forms of ``device`` (a click on it in the 3D view, or the picker)."""
        if device not in self.forms:
            return
        if self.picker.value != device:
            self.picker.value = device
        for name, (folder, _form) in self.forms.items():
            folder.visible = name == device

    def update(self, master: Mapping[str, Any],
               devices: Mapping[str, Mapping[str, Any]] | None = None) -> None:
        if devices is not None:
            self._snapshots = dict(devices)  # replaced whole: read from callback threads
        set_options(self.cable, cable_options(master, self._order))
        set_options(self.slave_power, slave_options(master, self._order))
        set_options(self.esc_slave, slave_options(master, self._order))
