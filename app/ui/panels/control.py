"""Coupler controls: power, CNF, fault injection, Reset fault, rotary switch, training causes.

Every callback only queues a device action (``CommandSender``) with the value of the change
that called it; what the device then does shows in the state panel and the 3D view of every
browser. Widgets are server-level, so a click in one browser moves the same widget in the
others; the widgets that are device values (Power, Hold CNF, Reset fault, rotary switch, cable,
Tbus) end up showing the model's value in every browser whatever the clicks
(:class:`app.ui.panels.widgets.Synced`).
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import viser

from app.ui.commands import CommandSender
from app.ui.panels.client_pick import ClientPick
from app.ui.panels.page_prop import PageProp
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import (
    DetailHint,
    Synced,
    UserChange,
    on_user_change,
    set_options,
    short_label_css,
)

CNF_HOLD_S = 3.0  # seed 000 §2: "almeno tre secondi"
CNF_PRESS_S = 3.5  # the button's press: comfortably past the threshold
CNF_SHORT_S = 1.0  # a press that must do nothing (training)
COUPLER_TARGET = "coupler (no module)"
NO_MODULE_TARGET = "(no module on the rail)"  # a module code before any module is there
# Seed 000 §6.17 / §7: writing 0x5200:1 commands the reset, "alzando il bit" (raising it); the
# coupler keeps the bit at 1 until it is written 0. The box mirrors the bit, so it stays ticked
# after a reset, which trainees read as a stuck reset: the hint and, while the bit is 1, a
# note under the box say what it is.
RESET_HINT = ("This box is the bit 0x5200:1 (Reset fault) as the coupler holds it. The reset "
              "acts on its rising edge: ticking it (0 → 1) resets a resettable alarm whose "
              "cause is gone (codes above 0x7F need a resync). The bit stays 1 afterwards: "
              "untick it (1 → 0) before the next reset.")
RESET_NOTE = ('<p class="fr-muted" id="fr-reset-note" style="font-size:0.8em;margin:0 0 4px 0">'
              "Reset fault bit 0x5200:1 = 1. A reset happens only on the rising edge "
              "(0 → 1), for a resettable alarm whose cause is gone. The box shows the bit: "
              "untick it before the next try.</p>")
MASTER_TARGETS = ("INIT", "PREOP", "SAFEOP", "OP")


@dataclass(frozen=True)
class FaultOption:
    table: str  # "coupler" (§7.5, byte 3) or "module" (§7.6, byte 2)
    code: int
    name: str
    description: str
    # The targets the code takes, the device's own answer (AlarmCode.on_coupler /
    # names_module): §7.5's 0x10-0x13 name no node, §7.6's codes always name a module.
    on_coupler: bool = True
    on_module: bool = True

    @property
    def label(self) -> str:
        """The code and the manual's name: what the box can show whole (the description is
        the box's hint, :class:`DetailHint`)."""
        return f"0x{self.code:02X} {self.name}"

    @property
    def detail(self) -> str:
        section = "§7.5" if self.table == "coupler" else "§7.6"
        return f"{self.label}: {self.description} (seed 000 {section})"

    @property
    def ref(self) -> str:
        """How inject_fault/clear_fault name it without ambiguity: ``coupler:0x04``."""
        return f"{self.table}:0x{self.code:02X}"


@dataclass(frozen=True)
class _FaultForm:
    """The instructor's fault injection rows of one connection (or the shared ones)."""

    table: Any
    fault: Any
    target: Any
    actions: Any


TABLE_LABELS = {"coupler": "coupler codes (§7.5)", "module": "module codes (§7.6)"}


def module_options(rail: Sequence[Mapping[str, Any]]) -> list[str]:
    """``"2 DI16"`` per slot (``"8 (empty)"`` for an empty one): the slot number leads."""
    return [f"{e['slot']} {e.get('type') or '(empty)'}" for e in rail]


def fault_targets(rail: Sequence[Mapping[str, Any]]) -> list[str]:
    """``"2 DI16"`` per module the coupler numbered (the module number of the emergency's byte
    0, which skips empty rail positions); rail positions before the first scan."""
    numbered = [(e["module_number"], e["type"]) for e in rail if e.get("module_number")]
    if not numbered:
        numbered = [(e["slot"], e["type"]) for e in rail if e.get("type")]
    return [f"{n} {t}" for n, t in numbered]


def taken_targets(fault: FaultOption | None, modules: Sequence[str]) -> list[str]:
    """The Target box's options for ``fault``: what the code takes, the device's own answer
    (seed 000 §7.5: 0x10-0x13 name no node, the coupler only; §7.6: the modules only)."""
    on_coupler = fault.on_coupler if fault is not None else True
    on_module = fault.on_module if fault is not None else True
    return [*([COUPLER_TARGET] if on_coupler else []),
            *(modules if on_module else [])] or [NO_MODULE_TARGET]


def _picked(widget: Any, client_id: int | None) -> str:
    """What ``widget`` holds on ``client_id``'s page (a ClientPick: the page's own)."""
    return widget.value_for(client_id) if isinstance(widget, ClientPick) else str(widget.value)


def option_slot(option: str) -> int | None:
    head = option.split(" ", 1)[0]
    return int(head) if head.isdigit() else None


class ControlPanel:
    def __init__(self, server: viser.ViserServer, sender: CommandSender, device_id: str,
                 faults: Sequence[FaultOption], rotary_range: tuple[int, int],
                 master_id: str | None = None) -> None:
        self._send = sender.send
        self._sender = sender
        self._server = server
        self._id = device_id
        self._faults = {t: [f for f in faults if f.table == t] for t in TABLE_LABELS}
        self._modules: list[str] = []  # fault_targets of the last snapshot
        # The Faults forms' writers: a pick (viser's threads) and the frame update. Each reads
        # the picks and the rail and writes the Target list (and moves the pick) under it, or
        # one wrote what it read before the other's write over it (a list of the rail before,
        # a Target the new code does not take) and the form kept it until the next frame.
        # Reentrant: an open rig's Table pick moves the page's code and shows the lists in one
        # step, and a widget assigned under it runs its callbacks at once in this thread
        # (viser 1.1.1).
        self._faults_lock = threading.RLock()
        gui = server.gui

        with gui.add_folder("Power and CNF"):
            self._power = gui.add_checkbox("Power", False, hint="24 V supply of the coupler")
            press = gui.add_button(f"Press CNF ({CNF_PRESS_S:g} s)", icon=viser.Icon.HAND_FINGER)
            short = gui.add_button(f"Tap CNF ({CNF_SHORT_S:g} s)",
                                   hint="shorter than 3 s: the coupler must ignore it")
            self._hold = gui.add_checkbox("Hold CNF", False,
                                          hint="CNF pressed while checked; release after 3 s")
            self._cnf_progress = gui.add_progress_bar(0.0, color="blue")

        # What makes a fault, or shows one outright (the two boxes follow the coupler): built
        # per instructor connection with a token, so a trainee's browser never gets them nor
        # what the instructor picks in them (app/ui/panels/per_client.py, docs/classroom.md).
        self._instructor = instructor_for(server)
        with gui.add_folder("Faults"):
            self._forms = self._instructor.part(self._fault_form)
            self._reset = gui.add_checkbox("Reset fault", False, hint=RESET_HINT)
            self._reset_note = gui.add_html("", visible=False)
            self._reset_note_bit: bool | None = None

        with gui.add_folder("Address and causes", expand_by_default=False):
            low, high = rotary_range
            self._rotary = gui.add_slider("Rotary switch", min=low, max=high, step=1,
                                          initial_value=max(low, 1))
            self._boxes = self._instructor.part(self._cause_boxes)
        shared = self._forms.each()[0] if self._instructor.shared else None
        boxes = self._boxes.each()[0] if self._instructor.shared else None
        # Open rig: the server-level widgets, as before (tests, Dashboard.instructor_widgets).
        self._table = shared.table if shared else None
        self._fault = shared.fault if shared else None
        self._target = shared.target if shared else None
        self._link = boxes[0].handle if boxes else None
        self._tbus_low = boxes[1].handle if boxes else None
        self.instructor_only = (shared.table.handle, shared.fault.handle, shared.target.handle,
                                shared.actions, self._link, self._tbus_low) \
            if shared and boxes else ()
        # Boxes whose longest option needs the room of a narrower label column (the dashboard's
        # widgets.short_label_css; a style row in the folder would be a row of its own).
        self.short_labels = (shared.fault.handle,) if shared else ()

        if master_id is not None:
            self._master_controls(gui, master_id)

        device = self._id
        self._power_sync = self._synced(
            self._power, lambda c, on: self._send(c, device, "power", {"on": bool(on)}))
        self._hold_sync = self._synced(
            self._hold, lambda c, down: self._send(c, device,
                                                   "press_cnf" if down else "release_cnf"))
        # §6.17: the box is the level of 0x5200:1; its rising edge resets the alarm.
        self._reset_sync = self._synced(
            self._reset, lambda c, on: self._send(c, device, "set_reset_fault", {"on": bool(on)}))
        self._rotary_sync = self._synced(
            self._rotary, lambda c, v: self._send(c, device, "set_rotary", {"value": int(v)}))

        @press.on_click
        def _(event: viser.GuiEvent) -> None:
            self._send(event.client, self._id, "hold_cnf", {"seconds": CNF_PRESS_S})

        @short.on_click
        def _(event: viser.GuiEvent) -> None:
            self._send(event.client, self._id, "hold_cnf", {"seconds": CNF_SHORT_S})

    def _fault_form(self, gui: Any) -> _FaultForm:
        if self._instructor.shared:
            return self._page_fault_form(gui)
        form = _FaultForm(gui.add_dropdown("Table", tuple(TABLE_LABELS.values())),
                          gui.add_dropdown("Fault", self._fault_labels("coupler")),
                          gui.add_dropdown("Target", (COUPLER_TARGET,)),
                          gui.add_button_group("Injection", ("Inject", "Clear")))
        gui.add_html(short_label_css([form.fault]))  # the Fault box's narrower label
        hint = DetailHint(form.fault, lambda: {
            f.label: f.detail for f in self._faults[self._table_key(form.table.value)]})

        @form.table.on_update
        def _(event: viser.GuiEvent) -> None:
            set_options(form.fault, list(self._fault_labels(self._table_key(form.table.value))))
            hint.refresh()
            self._offer_targets(form)

        @form.fault.on_update
        def _(event: viser.GuiEvent) -> None:
            self._offer_targets(form)

        self._on_inject(form)
        return form

    def _page_fault_form(self, gui: Any) -> _FaultForm:
        """An open rig's one form, its pickers each page's own (ClientPick): one operator's
        pick of the fault or module to inject moved every other page's, and what its Inject
        and Clear then sent. The Fault box offers each page the codes of its own Table, with
        the picked code's description as its hint, and the Target the targets its own code
        takes (PageProp)."""
        every = tuple(dict.fromkeys(label for table in TABLE_LABELS
                                    for label in self._fault_labels(table)))
        form = _FaultForm(
            ClientPick(self._server, gui.add_dropdown("Table", tuple(TABLE_LABELS.values()))),
            ClientPick(self._server, gui.add_dropdown(
                "Fault", every, initial_value=self._fault_labels("coupler")[0])),
            ClientPick(self._server, gui.add_dropdown("Target", (COUPLER_TARGET,))),
            gui.add_button_group("Injection", ("Inject", "Clear")))
        self._fault_options = PageProp(self._server, form.fault.handle, "options")
        self._fault_hints = PageProp(self._server, form.fault.handle, "hint")
        self._target_options = PageProp(self._server, form.target.handle, "options")

        def table_picked(client: viser.ClientHandle, label: str) -> None:
            with self._faults_lock:
                form.fault.set_for(client, self._fault_labels(self._table_key(label))[0])
                self._show_faults(form)

        form.table.on_pick(table_picked)
        form.fault.on_pick(lambda _client, _label: self._show_faults(form))
        self._on_inject(form)
        return form

    def _show_faults(self, form: _FaultForm) -> None:
        """Each page its Table's codes, its Fault's description and the targets its code
        takes (an open rig's form)."""
        def labels(client_id: int) -> tuple[str, ...]:
            return self._fault_labels(self._table_key(form.table.value_for(client_id)))

        def hint(client_id: int) -> str | None:
            fault = self._selected_fault(form, client_id)
            return None if fault is None else fault.detail

        with self._faults_lock:
            self._fault_options.show(labels)
            self._fault_hints.show(hint)
            self._show_targets(form)

    def _show_targets(self, form: _FaultForm) -> None:
        """Each page the targets its own code takes (§7.5 / §7.6); a page whose Target its
        code does not take moves to the first one it does, as the plain form's would."""
        modules = list(self._modules)
        offered: dict[int, tuple[str, ...]] = {}

        def targets(client_id: int) -> tuple[str, ...]:
            if client_id not in offered:
                offered[client_id] = tuple(taken_targets(
                    self._selected_fault(form, client_id), modules))
            return offered[client_id]

        self._target_options.show(targets)
        for client_id, client in self._server.get_clients().items():
            allowed = targets(client_id)
            if form.target.value_for(client_id) not in allowed:
                form.target.set_for(client, allowed[0])

    def _on_inject(self, form: _FaultForm) -> None:
        @form.actions.on_click
        async def _(event: viser.GuiEvent) -> None:
            # On viser's loop: the group's value is still the button of this click.
            verb = "inject_fault" if event.target.value == "Inject" else "clear_fault"
            fault = self._selected_fault(form, event.client_id)
            if fault is None:
                return
            # byte 0 of the emergency (§7): the clicking page's Target
            module = option_slot(_picked(form.target, event.client_id))
            target = self._id if module is None else f"{self._id}/{module}"
            self._send(event.client, target, verb, {"fault": fault.ref})

    def _cause_boxes(self, gui: Any) -> tuple[Synced, Synced]:
        device = self._id
        link = self._synced(gui.add_checkbox("EtherCAT cable in", True), lambda c, on: self._send(
            c, device, "link", {"connected": bool(on)}))
        tbus = self._synced(gui.add_checkbox("Tbus supply low", False), lambda c, low: self._send(
            c, device, "tbus_voltage", {"low": bool(low)}))
        return link, tbus

    def _synced(self, handle: Any, command: UserChange) -> Synced:
        return Synced(self._server, handle, self._sender, command)

    def _master_controls(self, gui: viser.GuiApi, master_id: str) -> None:
        """The built-in master: a resync (the only reset of codes above 0x7F, §7.5)."""
        with gui.add_folder("EtherCAT master", expand_by_default=False):
            resync = gui.add_button("Resync", hint="every slave through INIT and back; resets "
                                                   "alarms whose cause is gone (§7)")
            target = gui.add_dropdown("Target state", MASTER_TARGETS, initial_value="OP")

        @resync.on_click
        def _(event: viser.GuiEvent) -> None:
            self._send(event.client, master_id, "resync")

        on_user_change(target, lambda client, state: self._send(
            client, master_id, "set_target", {"state": state}))

    @staticmethod
    def _table_key(table: str) -> str:
        for key, label in TABLE_LABELS.items():
            if label == table:
                return key
        return "coupler"

    def _fault_labels(self, table: str) -> tuple[str, ...]:
        return tuple(f.label for f in self._faults[table]) or ("(no codes)",)

    def _selected_fault(self, form: _FaultForm, client_id: int | None) -> FaultOption | None:
        """The fault ``client_id``'s page picked (an open rig's pickers are each page's)."""
        picked = _picked(form.fault, client_id)
        for fault in self._faults[self._table_key(_picked(form.table, client_id))]:
            if fault.label == picked:
                return fault
        return None

    @property
    def reset_box(self) -> Any:
        return self._reset

    @property
    def reset_note(self) -> Any:
        return self._reset_note

    def update(self, snap: Mapping[str, Any]) -> None:
        self._power_sync.follow(bool(snap.get("powered")))
        cnf = snap.get("cnf") or {}
        self._hold_sync.follow(bool(cnf.get("pressed")))
        bit = bool(snap.get("reset_fault", False))
        if bit != self._reset_note_bit:  # before the box, which viser's loop sets later
            self._reset_note_bit = bit
            self._reset_note.content = RESET_NOTE if bit else ""
            self._reset_note.visible = bit
        self._reset_sync.follow(bit)
        held = float(cnf.get("held_s", 0.0)) if cnf.get("pressed") else 0.0
        progress = round(min(100.0, 100.0 * held / CNF_HOLD_S))
        if self._cnf_progress.value != progress:
            self._cnf_progress.value = progress
            # Green once the hold is long enough: releasing now starts the CNF procedure.
            self._cnf_progress.color = "green" if held >= CNF_HOLD_S else "blue"
        if "rotary_switch" in snap:
            self._rotary_sync.follow(int(snap["rotary_switch"]))
        # The coupler's own plug, not the line's link: after the master's pull_cable 0 the box
        # stays ticked (ticking it could not plug the master's cable back in).
        plugged = bool((snap.get("plugs") or [snap.get("link", True)])[0])
        for link, tbus in self._boxes.each():
            link.follow(plugged)
            tbus.follow(bool(snap.get("tbus_low", False)))
        self._modules = fault_targets(snap.get("rail") or [])
        for form in self._forms.each():
            if isinstance(form.target, ClientPick):  # an open rig's: each page's pick
                self._offer_every_target(form)
            else:
                self._offer_targets(form)

    def _offer_every_target(self, form: _FaultForm) -> None:
        """An open rig's Target: the server's options are what any code takes (a page's pick
        must be one of them), each page is offered what its own code takes (_show_targets)."""
        every = list(dict.fromkeys(target for faults in self._faults.values()
                                   for fault in faults
                                   for target in taken_targets(fault, self._modules)))
        before = form.target.options
        form.target.set_options(every)
        if form.target.options != before:  # went to every page, over each page's own
            self._target_options.overwritten()
        self._show_faults(form)

    def _offer_targets(self, form: _FaultForm) -> None:
        """Only the targets the picked code takes: a module pick for a code about no node
        was refused by the coupler once applied (§7.5)."""
        with self._faults_lock:
            set_options(form.target, taken_targets(self._selected_fault(form, None),
                                                   self._modules))
