"""The commands the Servo drive tab sends (a mixin of
:class:`~app.ui.drive.drive_panel.DrivePanel`).

Every control is a drive action (devices/servo/actions.py), queued through ``CommandSender``;
a sequence that must not be split (the positioner's Move, velocity with a new target) runs as
one function in the simulation thread. A read's or write's answer is parked here and shown by
the panel's ``update``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import viser

from app.classroom.roles import Role
from app.ui.commands import notify
from app.ui.drive.drive_options import leading_int, register_of
from app.ui.drive.drive_state import injected_names
from devices.servo import control
from devices.servo.registers import R

if TYPE_CHECKING:
    from app.ui.drive.drive_panel import DrivePanel

START_BITS = control.BIT5 | control.BIT6 | control.BIT7  # R00 bits 5..7: mode specific
JOG = {"Jog -": -1, "Jog 0": 0, "Jog +": 1}


def reset_refusal_text(why: str, injected: list[Mapping[str, Any]]) -> str:
    """A refused Alarm reset in words: the model's reason (what the drive shows, "the cause
    persists"), and for the instructor (``injected`` given only to them) which injected cause
    holds it; a trainee is never told a cause was injected (docs/classroom.md)."""
    names = injected_names(injected)
    if not names:
        return why
    return f"{why} · injected: {names} (Clear alarm removes it, then reset)"


class DriveCommands:
    """What each control of the tab sends to the page's drive."""

    def _do(self: DrivePanel, event: viser.GuiEvent, action: str, **args: Any) -> None:
        self._sender.send(event.client, self._target(event.client), action, args)

    def _jog(self: DrivePanel, event: viser.GuiEvent, direction: int) -> None:
        """Jog; when the model answers why the axis will not move (a drive without torque
        only switches to mode 3), the clicking page is told, naming the drive."""
        self._motion(event, "jog", direction=direction)

    def _motion(self: DrivePanel, event: viser.GuiEvent, action: str, **args: Any) -> None:
        """A motion command (jog, home, start); the model's answer why the axis will not
        move goes to the clicking page as a notice naming the drive. Home and Start used to
        say nothing, so after an alarm reset that left the axis released they did nothing
        with no word."""
        target, client = self._target(event.client), event.client
        self._sender.send(client, target, action, args,
                          done=self._motion_answer(client, f"{target}: {action}", target))

    @staticmethod
    def _motion_answer(client: viser.ClientHandle | None, title: str,
                       target: str) -> Callable[[Any], None]:
        def answered(why: Any) -> None:
            if why:
                notify(client, title, f"{target}: {why}")
        return answered

    def _alarm_reset(self: DrivePanel, event: viser.GuiEvent) -> None:
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

    def _apply(self: DrivePanel, client: viser.ClientHandle | None, action: str,
               args: dict[str, Any]) -> None:
        self._sender.send(client, self._target(client), action, args)

    def _sequence(self: DrivePanel, event: viser.GuiEvent, label: str,
                  steps: Callable[[Callable[..., Any]], Any],
                  done: Callable[[Any], None] | None = None) -> None:
        """Run ``steps(apply)`` in the simulation thread: no other command in between."""
        target = self._target(event.client)
        rig = self._runtime.rig

        def run() -> Any:
            return steps(lambda action, **args: rig.apply(target, action, args))

        self._sender.submit(event.client, f"{target}: {label}", run, done=done)

    def _positioner(self: DrivePanel, event: viser.GuiEvent, button: str) -> None:
        if button == "Start":
            self._motion(event, "start")
            return
        if button == "Stop":
            self._do(event, "stop")
            return
        position = int(self._field("position", event))
        relative = bool(self._field("relative", event))

        def steps(apply: Callable[..., Any]) -> Any:
            # As the seed's Modbus example does before 0x23: the start bits low first, so
            # that the start is a rising edge in both views whatever the last mode left.
            if int(apply("read_register", register=R.MODES_OF_OPERATION)) != 1:
                apply("set_mode", mode=1)
            r00 = int(apply("read_register", register=R.CONTROL_WORD))
            if r00 & (START_BITS | control.STP_CMD):
                apply("control_register", value=r00 & ~(START_BITS | control.STP_CMD))
            return apply("move", position=position, relative=relative)

        target = self._target(event.client)
        self._sequence(event, "move", steps,
                       done=self._motion_answer(event.client, f"{target}: move", target))

    def _run_velocity(self: DrivePanel, event: viser.GuiEvent) -> None:
        velocity = int(self._field("velocity", event))

        def steps(apply: Callable[..., Any]) -> None:
            if int(apply("read_register", register=R.MODES_OF_OPERATION)) != 3:
                apply("set_mode", mode=3)
            apply("write_register", register=R.TARGET_VELOCITY, value=velocity)

        self._sequence(event, "velocity", steps)

    def _field(self: DrivePanel, name: str, event: viser.GuiEvent) -> Any:
        """What the clicking page's form field ``name`` holds (app/ui/panels/client_form.py)."""
        return self._forms[name].value_of(event.client)

    def _park(self: DrivePanel, client: viser.ClientHandle | None, text: str) -> None:
        """The answer for the line under the boxes: the asking page's only."""
        client_id = getattr(client, "client_id", None)
        with self._result_lock:
            if client_id in self._server.get_clients():  # not one that left meanwhile
                self._page_results[client_id] = text

    def _read_or_write(self: DrivePanel, event: viser.GuiEvent, write: bool, kind: str,
                       key: int | str, label: str, typed: Any) -> None:
        """Read or write one register or parameter (``kind``) of the clicking page's drive
        (``typed``: the value its box holds); the answer is parked for the line under the
        boxes, named by ``label``."""
        target, client = self._target(event.client), event.client
        if write:
            value = int(typed)
            self._sender.send(client, target, f"write_{kind}", {kind: key, "value": value},
                              done=lambda _r: self._park(client, f"{label} = {value} written"))
        else:
            self._sender.send(client, target, f"read_{kind}", {kind: key},
                              done=lambda r: self._park(client, f"{label} = {r}"))

    def _register_access(self: DrivePanel, event: viser.GuiEvent, button: str) -> None:
        option = str(self._field("register", event))
        self._read_or_write(event, button == "Write register", "register", register_of(option),
                            option, self._field("register value", event))

    def _parameter_access(self: DrivePanel, event: viser.GuiEvent, button: str) -> None:
        name = str(self._field("parameter", event)).split(" ", 1)[0]
        self._read_or_write(event, button == "Write param.", "parameter", name, name,
                            self._field("parameter value", event))

    def _typed(self: DrivePanel, name: str, event: viser.GuiEvent) -> Any:
        """What the clicking page's c9 or c7 box holds."""
        return self._mirrors[name].value_for(event.client_id)

    def _write_fieldbus(self: DrivePanel, event: viser.GuiEvent) -> None:
        c9, c7 = leading_int(self._typed("c9", event)), int(self._typed("c7", event))

        def steps(apply: Callable[..., Any]) -> None:
            apply("write_parameter", parameter="c9", value=c9)
            apply("write_parameter", parameter="c7", value=c7)

        self._sequence(event, "c9 / c7", steps, done=lambda _r: self._park(
            event.client,
            f"c9 = {c9}, c7 = {c7} written: save, then power the drive off and on"))
