"""Servo drive controls: power, TEN / IEN, torque, mode, moves, jog, homing, alarms, load jam,
registers and parameters, fieldbus and flash.

The panel builds the controls and shows the drive's values (``update``); what the controls
send is ``drive_commands.py``, the instructor's alarm rows and fault form ``drive_faults.py``
(both mixins of :class:`DrivePanel`), the dropdowns' options and hints ``drive_options.py``.
Labels are unique across the dashboard ("Drive power", "Inject alarm") so that they never clash
with the coupler's controls.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import viser

from app.classroom.roles import makes_faults
from app.runtime import Runtime
from app.ui.commands import CommandSender
from app.ui.drive.drive_commands import JOG, DriveCommands
from app.ui.drive.drive_faults import DRIVE_KIND, DriveFaults
from app.ui.drive.drive_options import (
    FIELDBUS_OPTIONS,
    MODE_OPTIONS,
    PARAMETER_OPTIONS,
    REGISTER_OPTIONS,
    leading_int,
    mode_option,
    parameter_details,
    register_details,
    register_option,
)
from app.ui.panels.client_action_form import ClientActionForm
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_input import ClientMirror, ClientSynced
from app.ui.panels.client_pick import ClientHtml
from app.ui.panels.page_prop import PageProp
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import Synced, on_button
from app.ui.style import esc
from devices.device import Action
from devices.servo.modbus_map import NORMAL
from devices.servo.parameters import FIELDBUS_BY_C9, PARAMETER_BY_NAME
from devices.servo.registers import R

# The drive a page's controls command (None: no page, a new page's)
Target = Callable[[viser.ClientHandle | None], str]
Pick = Callable[[int | None], str]  # the drive a page shows, by its client id

NO_RESULT = '<p class="fr-muted">-</p>'
# The hints of each map, built once: each page's are looked up each frame
_REGISTER_HINTS = functools.cache(register_details)
_PARAMETER_HINTS = functools.cache(parameter_details)


def result_html(text: str) -> str:
    """The line under the register and parameter boxes: the last read's or write's answer."""
    return f'<p id="fr-drive-result" class="fr-note"><code>{esc(text)}</code></p>'


class DrivePanel(DriveCommands, DriveFaults):
    def __init__(self, server: viser.ViserServer, runtime: Runtime, sender: CommandSender,
                 target: Target, actions: Mapping[str, Action],
                 drive_ids: Sequence[str] = ()) -> None:
        """``drive_ids``: the drives the Servo drive picker offers. Several: each page commands
        and shows the drive it picked (``target(client)``, app/ui/panels/client_input.py),
        and with a token the instructor's forms get a Drive picker of their own."""
        self._runtime = runtime
        self._drive_ids = tuple(drive_ids)
        self._per_page = len(self._drive_ids) > 1
        self._devices: Mapping[str, Any] = {}  # the last frame's (update)
        self._sender = sender
        self._target = target
        self._fieldbus = "modbus"
        self._result_lock = threading.Lock()
        # Each page's answer, parked by a read's future (simulation thread), shown by update()
        self._page_results: dict[int, str] = {}
        self._injected: list[Mapping[str, Any]] = []  # the last frame's (snapshot injected)
        gui = server.gui

        with gui.add_folder("Drive power and torque"):
            self._power = gui.add_checkbox("Drive power", True, hint="the drive's supply")
            self._ten = gui.add_checkbox("TEN (24 V)", True, hint="hardware torque enable")
            self._ien = gui.add_checkbox("IEN (24 V)", True, hint="hardware motion enable")
            torque = gui.add_button_group("Torque", ("Enable", "Disable"))
            # seed 004 resets with the enable off: torque comes back with Enable only
            reset = gui.add_button("Alarm reset", hint="a 0 -> 1 -> 0 pulse of the reset bit; "
                                   "the axis stays released until Enable")
        with gui.add_folder("Motion"):
            self._mode = gui.add_dropdown("Mode", MODE_OPTIONS)
            self._position = gui.add_number("Target position", 0, step=1,
                                            min=-0x8000_0000, max=0x7FFF_FFFF)
            self._relative = gui.add_checkbox("Relative", False, hint="Inc_mod: from the "
                                              "last target")
            moves = gui.add_button_group("Positioner", ("Move", "Start", "Stop"))
            home = gui.add_button("Home", hint="mode 6 with R18 method, R19 offset, "
                                               "R20 / R21 speeds")
            self._velocity = gui.add_number("Target velocity", 1000, step=1,
                                            min=-0x8000_0000, max=0x7FFF_FFFF)
            run = gui.add_button("Run at velocity", hint="mode 3, R13 = target velocity")
            jog = gui.add_button_group("Jog", tuple(JOG))
        # What makes a fault, or shows one outright (the box follows the drive): the folder is
        # built per instructor connection with a token, so a trainee's browser never gets it
        # (app/ui/panels/per_client.py; docs/classroom.md).
        self._server = server
        instructor = instructor_for(server)
        self._alarms = instructor.part(self._alarm_form)
        shared = self._alarms.each()[0] if instructor.shared else None
        self.instructor_only = (shared.alarm.handle, shared.ops, shared.jam.handle) \
            if shared else ()
        # The longest names whole (widgets.short_label_css)
        self.short_labels = (shared.alarm.handle,) if shared else ()
        with gui.add_folder("Registers and parameters", expand_by_default=False):
            self._register = gui.add_dropdown("Register", REGISTER_OPTIONS,
                                              initial_value=register_option(R.PROFILE_VELOCITY))
            self._register_value = gui.add_number("Register value", 0, step=1,
                                                  min=-0x8000_0000, max=0xFFFF_FFFF)
            reg_ops = gui.add_button_group("Register access", ("Read register",
                                                               "Write register"))
            self._parameter = gui.add_dropdown("Parameter", PARAMETER_OPTIONS)
            self._parameter_value = gui.add_number("Parameter value", 0, step=1, min=0,
                                                   max=0xFFFF)
            par_ops = gui.add_button_group("Parameter access", ("Read param.", "Write param."))
            self._result_html = gui.add_html(NO_RESULT)
        with gui.add_folder("Fieldbus and flash", expand_by_default=False):
            self._c9 = gui.add_dropdown("Fieldbus (c9)", FIELDBUS_OPTIONS)
            c7 = PARAMETER_BY_NAME["c7"]
            self._c7 = gui.add_number("Node (c7)", 1, min=c7.low, max=c7.high, step=1)
            write_bus = gui.add_button("Write c9 and c7")
            save = gui.add_button("Save to flash",
                                  hint="only without torque or with IEN low; a few seconds")
            gui.add_html('<p class="fr-muted" style="font-size:0.75em">c9, c7 and n1 are read '
                         "at power-up: write, save, then switch Drive power off and on.</p>")
        with gui.add_folder("Other drive actions", expand_by_default=False):
            # With a token the actions that make a fault (roles.makes_faults: inject / clear
            # an alarm, jam the load, power off) are a form per instructor connection: in the
            # shared form a trainee's page got them, and the instructor's pick of one
            # (docs/classroom.md). An open rig keeps them in the one form. Its pick and
            # boxes are each page's: shared, a page's pick switched every page's form.
            faults = {} if instructor.shared else {
                n: a for n, a in actions.items() if makes_faults(DRIVE_KIND, n)}
            self._form = ClientActionForm(
                server, {n: a for n, a in actions.items() if n not in faults}, self._apply,
                label="Drive action")
            if faults:
                instructor.part(lambda gui: self._fault_form(gui, faults))

        # The boxes and the mode are drive values: every page ends up showing the selected
        # drive's (Synced). c9 and c7 are a form applied by "Write c9 and c7": what a user
        # types there must survive the next frame, and stay off the other pages
        # (ClientMirror).
        synced = self._synced_type()
        self._synced = {name: synced(server, handle, sender, command) for name, handle, command in (
            ("powered", self._power, lambda c, on: self._apply(c, "power", {"on": bool(on)})),
            ("ten", self._ten, lambda c, on: self._apply(c, "set_input",
                                                         {"name": "ten", "value": bool(on)})),
            ("ien", self._ien, lambda c, on: self._apply(c, "set_input",
                                                         {"name": "ien", "value": bool(on)})),
            ("mode", self._mode, lambda c, option: self._apply(
                c, "set_mode", {"mode": leading_int(option)})))}
        self._mirrors = {name: ClientMirror(server, handle)  # each page's, one drive too
                         for name, handle in (("c9", self._c9), ("c7", self._c7))}
        # The form fields, their hints and the answer line are each page's, on every rig: a
        # trainee's register number and read result stayed off the others' (a rig with one
        # drive too, where there is no picker).
        self._forms = {name: ClientForm(server, handle) for name, handle in (
            ("position", self._position), ("relative", self._relative),
            ("velocity", self._velocity), ("register", self._register),
            ("register value", self._register_value), ("parameter", self._parameter),
            ("parameter value", self._parameter_value))}
        self._results = ClientHtml(server, self._result_html)
        self._hints = (PageProp(server, self._register, "hint"),
                       PageProp(server, self._parameter, "hint"))
        # A new page's, until its own reach it
        self._register.hint = _REGISTER_HINTS(NORMAL).get(str(self._register.value))
        self._parameter.hint = _PARAMETER_HINTS(NORMAL).get(str(self._parameter.value))

        on_button(torque, lambda e, b: self._do(e, "enable", on=b == "Enable"))
        reset.on_click(lambda e: self._alarm_reset(e))
        home.on_click(lambda e: self._motion(e, "home"))
        on_button(jog, lambda e, b: self._jog(e, JOG[b]))
        on_button(moves, self._positioner)
        run.on_click(lambda e: self._run_velocity(e))
        on_button(reg_ops, self._register_access)
        on_button(par_ops, self._parameter_access)
        write_bus.on_click(lambda e: self._write_fieldbus(e))
        save.on_click(lambda e: self._do(e, "save"))

    def _synced_type(self) -> Any:
        """Synced, or ClientSynced when each page shows its own drive."""
        return ClientSynced if self._per_page else Synced

    # ---- view -----------------------------------------------------------------------------
    def update(self, snap: Mapping[str, Any],
               devices: Mapping[str, Any] | None = None, pick_of: Pick | None = None) -> None:
        """``snap``: the snapshot of the drive a new page shows; ``devices``: every device's
        (an instructor's form with its own Drive picker shows its drive's); ``pick_of``:
        the drive each page shows (several drives)."""
        devices = devices or {}
        self._devices = devices
        self._injected = list(snap.get("injected") or [])
        fieldbus = self._fieldbus = str(snap.get("fieldbus", self._fieldbus))

        def page(client_id: int | None) -> Mapping[str, Any]:
            """The snapshot of the drive ``client_id``'s page shows."""
            if pick_of is None or client_id is None:
                return snap
            return devices.get(pick_of(client_id)) or {}

        for name in ("powered", "ten", "ien"):
            self._follow(self._synced[name], lambda s, n=name: bool(s.get(n)), page)
        self._follow_alarm_forms(snap, devices, page)
        self._follow(self._synced["mode"], lambda s: mode_option(s.get("mode")), page)
        self._mirror("c9", lambda s: next(
            (o for o in FIELDBUS_OPTIONS
             if FIELDBUS_BY_C9.get(leading_int(o)) == s.get("fieldbus", fieldbus)), None), page)
        self._mirror("c7", lambda s: int(s["node_id"]) if s.get("node_id") is not None
                     else None, page)
        self._show_pages(page)

    def _show_pages(self, page: Callable[[int | None], Mapping[str, Any]]) -> None:
        """Each page's hints (its register and parameter under its drive's map, ch. 2) and
        its last answer."""
        def address_map(client_id: int) -> str:
            return str(page(client_id).get("modbus_map", NORMAL))

        forms = self._forms
        registers, parameters = self._hints
        registers.show(lambda c: _REGISTER_HINTS(address_map(c)).get(
            str(forms["register"].value_for(c))))
        parameters.show(lambda c: _PARAMETER_HINTS(address_map(c)).get(
            str(forms["parameter"].value_for(c))))
        clients = self._server.get_clients()
        with self._result_lock:
            for gone in set(self._page_results) - set(clients):
                del self._page_results[gone]
            results = dict(self._page_results)
        self._results.show(lambda c: result_html(results[c]) if c in results else NO_RESULT)

    @staticmethod
    def _follow(synced: Synced | ClientSynced, value: Callable[[Mapping[str, Any]], Any],
                page: Callable[[int | None], Mapping[str, Any]]) -> None:
        """The model's value (None: the drive has none) into a Synced widget: each page its
        drive's."""
        if isinstance(synced, ClientSynced):
            synced.follow_each(lambda client_id: value(page(client_id)))
        elif (shown := value(page(None))) is not None:
            synced.follow(shown)

    def _mirror(self, name: str, value: Callable[[Mapping[str, Any]], Any],
                page: Callable[[int | None], Mapping[str, Any]]) -> None:
        """c9 / c7 (what the drive latched at power-up) into each page's form field."""
        self._mirrors[name].follow_each(lambda client_id: value(page(client_id)))

    def forget(self, client_id: int | None = None) -> None:
        """Another drive was selected (on ``client_id``'s page, every page's when None): take
        its c9 and c7 into the form. (A Synced widget at rest already shows the last value it
        followed, so it needs nothing: the next frame's value, the new drive's, is shown when
        it differs.)"""
        for mirror in self._mirrors.values():
            mirror.forget(client_id)
