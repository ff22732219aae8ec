"""Servo drive controls: power, TEN / IEN, torque, mode, moves, jog, homing, alarms, load jam,
registers and parameters, fieldbus and flash.

Every control is a drive action (devices/servo/actions.py), queued through ``CommandSender``;
a sequence that must not be split (the positioner's Move, velocity with a new target) runs as
one function in the simulation thread. Labels are unique across the dashboard ("Drive power",
"Inject alarm") so that they never clash with the coupler's controls.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import viser

from app.classroom.roles import Role, makes_faults
from app.runtime import Runtime
from app.ui.commands import CommandSender, notify
from app.ui.drive.drive_state import injected_names
from app.ui.panels.action_form import ActionForm
from app.ui.panels.client_input import ClientMirror, ClientSynced
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import DetailHint, Mirror, Synced, set_options, short_label_css
from app.ui.style import esc
from devices.device import Action
from devices.servo import control
from devices.servo.alarms import alarm_table
from devices.servo.modbus_map import NORMAL, SIEMENS, parameter_address, register_address
from devices.servo.parameters import (
    FIELDBUS_BY_C9,
    FIELDBUS_NAMES,
    PARAMETER_BY_NAME,
    PARAMETERS,
)
from devices.servo.registers import MODE_NAMES, REGISTERS, R

# The drive a page's controls command (None: no page, a new page's)
Target = Callable[[viser.ClientHandle | None], str]
Pick = Callable[[int | None], str]  # the drive a page shows, by its client id

MODE_OPTIONS = tuple(f"{mode} {name}" for mode, name in MODE_NAMES.items())
REGISTER_OPTIONS = tuple(f"R{n:02d} {spec.name}" for n, spec in sorted(REGISTERS.items()))
PARAMETER_OPTIONS = tuple(f"{spec.name} {spec.meaning}" for spec in PARAMETERS.values())
FIELDBUS_OPTIONS = tuple(f"{code} {FIELDBUS_NAMES[name]}"
                         for code, name in FIELDBUS_BY_C9.items())
START_BITS = control.BIT5 | control.BIT6 | control.BIT7  # R00 bits 5..7: mode specific
JOG = {"Jog -": -1, "Jog 0": 0, "Jog +": 1}
DRIVE_KIND = "servo"  # the drives' kind in app.classroom.roles


def alarm_details(fieldbus: str) -> dict[str, str]:
    """``"16 FOLLOWING_ERROR"`` -> ``"16 FOLLOWING_ERROR: maximum position ..."`` for every
    alarm of the drive with this fieldbus (ch. 3, ch. 5; ch. 6 for Profinet), in code order:
    the list shows the labels, the box's hint the description (:class:`DetailHint`)."""
    alarms = sorted(alarm_table(fieldbus).values(), key=lambda a: a.code)
    return {f"{a.code} {a.name}": f"{a.code} {a.name}: {a.description}" for a in alarms}


def modbus_words(address: int, address_map: str) -> str:
    """A Modbus address as the manual writes it under the map: hex in the normal one (ch. 1),
    decimal and hex with the map named in the Siemens one (ch. 2: "40001 + 1 = 40002 =
    0x9C42")."""
    if address_map == SIEMENS:
        return f"Modbus {address} = 0x{address:04X} (e3 = 9, Siemens map)"
    return f"Modbus 0x{address:04X}"


def register_details(address_map: str = NORMAL) -> dict[str, str]:
    """``"R24 master_encoder_increments"`` -> its range, access and Modbus address under the
    drive's map (ch. 1 "Registri", ch. 2 "Estensione della mappatura"): the box holds about
    25 characters, so the hint carries the label whole."""
    out = {}
    for n, spec in sorted(REGISTERS.items()):
        access = ("read only" if not spec.writable
                  else "kept by Save to flash" if spec.saveable else "not saved")
        where = modbus_words(register_address(n, address_map), address_map)
        out[f"R{n:02d} {spec.name}"] = (f"R{n:02d} {spec.name}: {spec.low}..{spec.high}, "
                                        f"{access}; {where}")
    return out


def parameter_details(address_map: str = NORMAL) -> dict[str, str]:
    """``"c9 operating mode / fieldbus"`` -> its range, default and Modbus address under the
    drive's map (ch. 1 "Parametri", ch. 2), and whether it acts only at the next power-up."""
    out = {}
    for spec in PARAMETERS.values():
        unit = " %" if spec.unit == "%" else ""
        when = "; read at power-up" if spec.power_up else ""
        access = "" if spec.writable else ", read only"
        where = modbus_words(parameter_address(spec.address, address_map), address_map)
        out[f"{spec.name} {spec.meaning}"] = (
            f"{spec.name} {spec.meaning}: {spec.low}..{spec.high}{unit}, default "
            f"{spec.default}{access}{when}; {where}")
    return out


def reset_refusal_text(why: str, injected: list[Mapping[str, Any]]) -> str:
    """A refused Alarm reset in words: the model's reason (what the drive shows, "the cause
    persists"), and for the instructor (``injected`` given only to them) which injected cause
    holds it; a trainee is never told a cause was injected (docs/classroom.md)."""
    names = injected_names(injected)
    if not names:
        return why
    return f"{why} · injected: {names} (Clear alarm removes it, then reset)"


def alarm_options(fieldbus: str) -> tuple[str, ...]:
    return tuple(alarm_details(fieldbus))


def leading_int(option: str) -> int:
    """The number an option starts with: ``"-127 analog reference"`` -> -127."""
    return int(option.split(" ", 1)[0])


def register_of(option: str) -> int:
    return int(option.split(" ", 1)[0][1:])


def register_option(n: int) -> str:
    return next(o for o in REGISTER_OPTIONS if register_of(o) == n)


def mode_option(mode: Any) -> str | None:
    return next((o for o in MODE_OPTIONS if leading_int(o) == mode), None)


def on_button(group: Any, fn: Callable[[viser.GuiEvent, str], None]) -> None:
    """Call ``fn(event, button)`` for each click on a button group, with the button clicked.

    A coroutine, so it runs on viser's event loop as the click arrives, while the group's value
    is still this click's button (a plain callback runs later in a thread pool and can read the
    next click's: Enable, Disable commanded as Disable, Disable). ``fn`` must not block."""
    async def clicked(event: viser.GuiEvent) -> None:
        fn(event, str(event.target.value))

    group.on_click(clicked)


@dataclass
class _AlarmForm:
    """The instructor's alarm rows of one connection (or the shared ones); ``drive``: its own
    Drive picker (a token and several drives), None when the rows act on the shared one."""

    alarm: Any
    ops: Any
    jam: Synced | ClientSynced
    hint: DetailHint
    drive: Any = None
    fieldbus: list[str] = field(default_factory=lambda: ["modbus"])  # its drive's, as shown


class DrivePanel:
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
        self._modbus_map = NORMAL  # the drive's (snapshot modbus_map): the address hints
        self._result_lock = threading.Lock()
        self._result = ""  # parked by a read's future (simulation thread), shown by update()
        self._shown_result: str | None = None
        self._injected: list[Mapping[str, Any]] = []  # the last frame's (snapshot injected)
        gui = server.gui

        with gui.add_folder("Drive power and torque"):
            self._power = gui.add_checkbox("Drive power", True, hint="the drive's supply")
            self._ten = gui.add_checkbox("TEN (24 V)", True, hint="hardware torque enable")
            self._ien = gui.add_checkbox("IEN (24 V)", True, hint="hardware motion enable")
            torque = gui.add_button_group("Torque", ("Enable", "Disable"))
            reset = gui.add_button("Alarm reset", hint="a 0 -> 1 -> 0 pulse of the reset bit")
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
        self.instructor_only = (shared.alarm, shared.ops, shared.jam.handle) if shared else ()
        # The longest names whole (widgets.short_label_css)
        self.short_labels = (shared.alarm,) if shared else ()
        with gui.add_folder("Registers and parameters", expand_by_default=False):
            self._register = gui.add_dropdown("Register", REGISTER_OPTIONS,
                                              initial_value=register_option(R.PROFILE_VELOCITY))
            self._register_value = gui.add_number("Register value", 0, step=1,
                                                  min=-0x8000_0000, max=0xFFFF_FFFF)
            reg_ops = gui.add_button_group("Register access", ("Read register",
                                                               "Write register"))
            self._register_hint = DetailHint(self._register,
                                             lambda: register_details(self._modbus_map))
            self._parameter = gui.add_dropdown("Parameter", PARAMETER_OPTIONS)
            self._parameter_hint = DetailHint(self._parameter,
                                              lambda: parameter_details(self._modbus_map))
            self._parameter_value = gui.add_number("Parameter value", 0, step=1, min=0,
                                                   max=0xFFFF)
            par_ops = gui.add_button_group("Parameter access", ("Read param.", "Write param."))
            self._result_html = gui.add_html('<p class="fr-muted">-</p>')
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
            # (docs/classroom.md). An open rig keeps the one form.
            faults = {} if instructor.shared else {
                n: a for n, a in actions.items() if makes_faults(DRIVE_KIND, n)}
            self._form = ActionForm(gui, {n: a for n, a in actions.items() if n not in faults},
                                    self._apply, label="Drive action")
            if faults:
                instructor.part(lambda gui: self._fault_form(gui, faults))

        # The boxes and the mode are drive values: every page ends up showing the selected
        # drive's (Synced). c9 and c7 are a form applied by "Write c9 and c7": what a user
        # types there must survive the next frame (Mirror).
        synced = self._synced_type()
        self._synced = {name: synced(server, handle, sender, command) for name, handle, command in (
            ("powered", self._power, lambda c, on: self._apply(c, "power", {"on": bool(on)})),
            ("ten", self._ten, lambda c, on: self._apply(c, "set_input",
                                                         {"name": "ten", "value": bool(on)})),
            ("ien", self._ien, lambda c, on: self._apply(c, "set_input",
                                                         {"name": "ien", "value": bool(on)})),
            ("mode", self._mode, lambda c, option: self._apply(
                c, "set_mode", {"mode": leading_int(option)})))}
        self._mirrors: dict[str, Mirror | ClientMirror] = {
            name: ClientMirror(server, handle) if self._per_page else Mirror(handle)
            for name, handle in (("c9", self._c9), ("c7", self._c7))}

        on_button(torque, lambda e, b: self._do(e, "enable", on=b == "Enable"))
        reset.on_click(lambda e: self._alarm_reset(e))
        home.on_click(lambda e: self._do(e, "home"))
        on_button(jog, lambda e, b: self._jog(e, JOG[b]))
        on_button(moves, self._positioner)
        run.on_click(lambda e: self._run_velocity(e))
        on_button(reg_ops, self._register_access)
        on_button(par_ops, self._parameter_access)
        write_bus.on_click(lambda e: self._write_fieldbus(e))
        save.on_click(lambda e: self._do(e, "save"))

    # ---- commands -----------------------------------------------------------------------
    def _do(self, event: viser.GuiEvent, action: str, **args: Any) -> None:
        self._sender.send(event.client, self._target(event.client), action, args)

    def _synced_type(self) -> Any:
        """Synced, or ClientSynced when each page shows its own drive."""
        return ClientSynced if self._per_page else Synced

    def _jog(self, event: viser.GuiEvent, direction: int) -> None:
        """Jog; when the model answers why the axis will not move (a drive without torque
        only switches to mode 3), the clicking page is told, naming the drive."""
        target, client = self._target(event.client), event.client

        def answered(why: Any) -> None:
            if why:
                notify(client, f"{target}: jog", f"{target}: {why}")

        self._sender.send(client, target, "jog", {"direction": direction}, done=answered)

    def _alarm_reset(self, event: viser.GuiEvent) -> None:
        """Alarm reset; when the drive stays in Fault the clicking page is told why (the model's
        answer), and an instructor also which injected cause holds it."""
        target, client = self._target(event.client), event.client
        instructor = self._sender.role(client) is Role.INSTRUCTOR
        injected = list((self._devices.get(target) or {}).get("injected") or []) \
            if self._per_page else self._injected

        def answered(why: Any) -> None:
            if why:
                text = reset_refusal_text(str(why), injected if instructor else [])
                notify(client, f"{target}: alarm reset refused", text, error=True)

        self._sender.send(client, target, "alarm_reset", {}, done=answered)

    def _apply(self, client: viser.ClientHandle | None, action: str,
               args: dict[str, Any]) -> None:
        self._sender.send(client, self._target(client), action, args)

    def _sequence(self, event: viser.GuiEvent, label: str,
                  steps: Callable[[Callable[..., Any]], Any],
                  done: Callable[[Any], None] | None = None) -> None:
        """Run ``steps(apply)`` in the simulation thread: no other command in between."""
        target = self._target(event.client)
        rig = self._runtime.rig

        def run() -> Any:
            return steps(lambda action, **args: rig.apply(target, action, args))

        self._sender.submit(event.client, f"{target}: {label}", run, done=done)

    def _positioner(self, event: viser.GuiEvent, button: str) -> None:
        if button == "Start":
            self._do(event, "start")
            return
        if button == "Stop":
            self._do(event, "stop")
            return
        position, relative = int(self._position.value), bool(self._relative.value)

        def steps(apply: Callable[..., Any]) -> None:
            # As the seed's Modbus example does before 0x23: the start bits low first, so
            # that the start is a rising edge in both views whatever the last mode left.
            if int(apply("read_register", register=R.MODES_OF_OPERATION)) != 1:
                apply("set_mode", mode=1)
            r00 = int(apply("read_register", register=R.CONTROL_WORD))
            if r00 & (START_BITS | control.STP_CMD):
                apply("control_register", value=r00 & ~(START_BITS | control.STP_CMD))
            apply("move", position=position, relative=relative)

        self._sequence(event, "move", steps)

    def _run_velocity(self, event: viser.GuiEvent) -> None:
        velocity = int(self._velocity.value)

        def steps(apply: Callable[..., Any]) -> None:
            if int(apply("read_register", register=R.MODES_OF_OPERATION)) != 3:
                apply("set_mode", mode=3)
            apply("write_register", register=R.TARGET_VELOCITY, value=velocity)

        self._sequence(event, "velocity", steps)

    def _park(self, text: str) -> None:
        with self._result_lock:
            self._result = text

    def _register_access(self, event: viser.GuiEvent, button: str) -> None:
        option = self._register.value
        n = register_of(option)
        if button == "Write register":
            value = int(self._register_value.value)
            self._sender.send(event.client, self._target(event.client), "write_register",
                              {"register": n, "value": value},
                              done=lambda _r: self._park(f"{option} = {value} written"))
        else:
            self._sender.send(event.client, self._target(event.client), "read_register",
                              {"register": n},
                              done=lambda r: self._park(f"{option} = {r}"))

    def _parameter_access(self, event: viser.GuiEvent, button: str) -> None:
        name = self._parameter.value.split(" ", 1)[0]
        if button == "Write param.":
            value = int(self._parameter_value.value)
            self._sender.send(event.client, self._target(event.client), "write_parameter",
                              {"parameter": name, "value": value},
                              done=lambda _r: self._park(f"{name} = {value} written"))
        else:
            self._sender.send(event.client, self._target(event.client), "read_parameter",
                              {"parameter": name}, done=lambda r: self._park(f"{name} = {r}"))

    def _typed(self, name: str, event: viser.GuiEvent) -> Any:
        """What the clicking page's c9 or c7 box holds."""
        mirror = self._mirrors[name]
        return mirror.value_for(event.client_id) if isinstance(mirror, ClientMirror) \
            else mirror.handle.value

    def _write_fieldbus(self, event: viser.GuiEvent) -> None:
        c9, c7 = leading_int(self._typed("c9", event)), int(self._typed("c7", event))

        def steps(apply: Callable[..., Any]) -> None:
            apply("write_parameter", parameter="c9", value=c9)
            apply("write_parameter", parameter="c7", value=c7)

        self._sequence(event, "c9 / c7", steps, done=lambda _r: self._park(
            f"c9 = {c9}, c7 = {c7} written: save, then power the drive off and on"))

    def _own_drive(self, gui: Any) -> Any:
        """With a token and several drives, an instructor's form gets a Drive picker of its
        own: on the shared Servo drive picker the instructor's pick of the drive to jam or
        alarm went to every trainee's page (docs/classroom.md). None: the shared one."""
        if instructor_for(self._server).shared or len(self._drive_ids) < 2:
            return None
        return gui.add_dropdown("Drive", self._drive_ids, initial_value=self._target(None),
                                hint="the drive this form acts on")

    def _send_to(self, own: Any, client: viser.ClientHandle | None, action: str,
                 args: dict[str, Any], confirm: bool = False) -> None:
        target = self._target(client) if own is None else str(own.value)
        self._sender.send(client, target, action, args, confirm=confirm)

    def _alarm_form(self, gui: Any) -> _AlarmForm:
        with gui.add_folder("Alarms and load"):
            own = self._own_drive(gui)
            fieldbus = [self._fieldbus]
            alarm = gui.add_dropdown("Alarm", alarm_options(fieldbus[0]))
            ops = gui.add_button_group("Alarm cause", ("Inject alarm", "Clear alarm"))
            jam = gui.add_checkbox("Load jammed", False, hint="the load cannot move: "
                                   "following error, alarm 16")
        if not instructor_for(self._server).shared:  # per client: the narrower label
            gui.add_html(short_label_css([alarm]))
        # The shared form (an open rig) shows each page its own drive's jam
        jammed = Synced if own is not None else self._synced_type()
        form = _AlarmForm(alarm, ops, jammed(self._server, jam, self._sender, lambda c, on: (
            self._send_to(own, c, "jam_load", {"active": bool(on)}))),
            DetailHint(alarm, lambda: alarm_details(fieldbus[0])), own, fieldbus)
        on_button(ops, lambda e, b: self._send_to(
            own, e.client, "inject_alarm" if b == "Inject alarm" else "clear_alarm",
            {"code": str(leading_int(alarm.value))}))
        return form

    def _fault_form(self, gui: Any, faults: Mapping[str, Action]) -> ActionForm:
        with gui.add_folder("Drive faults", expand_by_default=False):
            own = self._own_drive(gui)
            return ActionForm(gui, faults, lambda c, name, args: self._send_to(
                own, c, name, args, confirm=True), label="Fault action")

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
        address_map = str(snap.get("modbus_map", self._modbus_map))
        if address_map != self._modbus_map:  # e3 = 9 moves every address (ch. 2)
            self._modbus_map = address_map
            self._register_hint.refresh()
            self._parameter_hint.refresh()

        def page(client_id: int | None) -> Mapping[str, Any]:
            """The snapshot of the drive ``client_id``'s page shows."""
            if pick_of is None or client_id is None:
                return snap
            return devices.get(pick_of(client_id)) or {}

        for name in ("powered", "ten", "ien"):
            self._follow(self._synced[name], lambda s, n=name: bool(s.get(n)), page)
        for form in self._alarms.each():
            own = snap if form.drive is None else devices.get(str(form.drive.value))
            own = own or {}
            bus = str(own.get("fieldbus", form.fieldbus[0]))
            if bus != form.fieldbus[0]:  # Profinet numbers 30..33 differently (ch. 6)
                form.fieldbus[0] = bus
                set_options(form.alarm, list(alarm_options(bus)))
                form.hint.refresh()
            if form.drive is None:
                self._follow(form.jam, lambda s: bool(s.get("jammed")), page)
            else:
                form.jam.follow(bool(own.get("jammed")))
        self._follow(self._synced["mode"], lambda s: mode_option(s.get("mode")), page)
        self._mirror("c9", lambda s: next(
            (o for o in FIELDBUS_OPTIONS
             if FIELDBUS_BY_C9.get(leading_int(o)) == s.get("fieldbus", fieldbus)), None), page)
        self._mirror("c7", lambda s: int(s["node_id"]) if s.get("node_id") is not None
                     else None, page)
        with self._result_lock:
            result = self._result
        if result != self._shown_result:
            self._result_html.content = ('<p id="fr-drive-result" class="fr-note">'
                                         f"<code>{esc(result)}</code></p>")
            self._shown_result = result

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
        """c9 / c7 (what the drive latched at power-up) into its form field."""
        mirror = self._mirrors[name]
        if isinstance(mirror, ClientMirror):
            mirror.follow_each(lambda client_id: value(page(client_id)))
        elif (shown := value(page(None))) is not None:
            mirror.follow(shown)

    def forget(self, client_id: int | None = None) -> None:
        """Another drive was selected (on ``client_id``'s page, every page's when None): take
        its c9 and c7 into the form. (A Synced widget at rest already shows the last value it
        followed, so it needs nothing: the next frame's value, the new drive's, is shown when
        it differs.)"""
        for mirror in self._mirrors.values():
            if isinstance(mirror, ClientMirror):
                mirror.forget(client_id)
            else:
                mirror.forget()
