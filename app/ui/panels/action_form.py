"""A form generated from a device's action table: pick an action, fill its parameters, apply.

The FastCAT's module actions (set an input, an analog value, an encoder fault, ...) are data
(:class:`devices.device.Action` / :class:`~devices.device.Param`), so the dashboard lists them
without knowing device logic, and a module action added to a model appears here unchanged.

An :class:`ActionForm` is one form for whoever sees it: an instructor connection's own copy
(*Module faults*, *Slave faults*, *Drive faults*). A form several pages share is a
:class:`app.ui.panels.client_action_form.ClientActionForm`, each page's own.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any

import viser

from app.ui.commands import notify
from devices.device import Action, CommandError, Param

# Called with (client, action name, args) when the user applies the form.
Apply = Callable[[viser.ClientHandle | None, str, dict[str, Any]], None]
# The target device's latest snapshot, read when a form is built (Param.current).
Current = Callable[[], Mapping[str, Any] | None]

MISSING = object()


def current_value(snapshot: Mapping[str, Any] | None, key: str) -> Any:
    """The value at a dotted key of a snapshot ("switches.dil1"), or MISSING."""
    value: Any = snapshot
    for part in key.split(".") if key else ():
        if not isinstance(value, Mapping) or part not in value:
            return MISSING
        value = value[part]
    return value if key else MISSING


def blank_allowed(p: Param) -> bool:
    """An optional parameter with no default: "not given" means something to the device (the
    CPX-E-EC's short_circuit without channel is the sensor supply, inject_fault without sm a
    fault of no sync manager). A number box always holds a number (viser keeps the last one
    when emptied), so it went as 0: such a parameter is a text box, blank = left out."""
    return not p.required and p.default is None and not p.choices and p.type is not bool


def param_widget(gui: viser.GuiApi, p: Param, now: Any = MISSING) -> Any:
    """``now``: the value the device has now (Param.current); else the default."""
    if now is not MISSING:
        with contextlib.suppress(CommandError):  # one the form cannot hold: the default
            p = replace(p, default=p.check(now))
    hint = p.doc or None
    if blank_allowed(p):
        return gui.add_text(p.name, "", hint=f"{p.doc + '; ' if p.doc else ''}blank: not given")
    if p.choices:
        options = tuple(str(c) for c in p.choices)
        initial = str(p.default) if p.default is not None and str(p.default) in options else None
        return gui.add_dropdown(p.name, options, initial_value=initial, hint=hint)
    if p.type is bool:
        return gui.add_checkbox(p.name, bool(p.default), hint=hint)
    if p.type in (int, float):
        initial = p.default if p.default is not None else (p.low if p.low is not None else 0)
        step = 1 if p.type is int else None
        return gui.add_number(p.name, p.type(initial), min=p.low, max=p.high, step=step,
                              hint=hint)
    return gui.add_text(p.name, "" if p.default is None else str(p.default), hint=hint)


def param_value(p: Param, value: Any) -> Any:
    """What a parameter's widget holds (``value``), as the action takes it."""
    if p.choices:
        for choice in p.choices:
            if str(choice) == value:
                return choice
    if p.type is int and isinstance(value, str):  # a blank-able box: "3", "0x3"
        return int(value.strip(), 0)
    if p.type is int:
        return int(value)
    if p.type is float:
        return float(value)
    return value


class ActionForm:
    def __init__(self, gui: viser.GuiApi, actions: Mapping[str, Action], apply: Apply,
                 label: str = "Action", current: Current | None = None) -> None:
        """``current``: the target device's latest snapshot, for the parameters that say
        where their present value is (Param.current)."""
        self._gui = gui
        self._current = current
        self._actions = dict(sorted(actions.items()))
        self._apply = apply
        names = tuple(self._actions) or ("(none)",)
        self._choice = gui.add_dropdown(label, names)
        self._params = gui.add_folder("Parameters", expand_by_default=True)
        self._button = gui.add_button("Apply", disabled=not self._actions)
        self._widgets: list[tuple[Param, Any]] = []
        self._built_for: str | None = None
        # The form's writers: a pick (viser stores it, then its callback runs in viser's
        # threads) and the frame update's restrict (the dashboard thread). Each reads the pick
        # and the list and writes under it. Reentrant: assigning the pick runs _picked at once
        # in the assigning thread (viser 1.1.1), under the lock its writer holds.
        self._lock = threading.RLock()
        self._build()

        @self._choice.on_update
        def _(event: viser.GuiEvent) -> None:
            self._picked()

        @self._button.on_click
        def _(event: viser.GuiEvent) -> None:
            self.submit(event.client)

    @property
    def choice(self) -> Any:
        """The action picker."""
        return self._choice

    @property
    def handles(self) -> tuple[Any, ...]:
        """The form's own widgets: picker, Parameters folder (rebuilt inside), Apply."""
        return (self._choice, self._params, self._button)

    def options(self) -> tuple[str, ...]:
        return tuple(self._choice.options)

    def values(self) -> dict[str, Any]:
        """What the parameter widgets hold now, by parameter name."""
        with self._lock:
            return {p.name: handle.value for p, handle in self._widgets}

    def restrict(self, names: Sequence[str]) -> None:
        """Offer only these actions (those the selected module accepts). The pick stays where
        the list holds it, else moves to the list's first: viser's options setter reads the
        pick as it is then. A pick read before the list was written and written back after
        it undid a pick made in between."""
        options = tuple(n for n in self._actions if n in set(names)) or ("(none)",)
        with self._lock:
            if tuple(self._choice.options) != options:
                self._choice.options = options
            self._button.disabled = options == ("(none)",)
            self._build()

    def _picked(self) -> None:
        """A pick the list does not hold (made on the page's list before restrict's reached
        it) moves to the list's first, as restrict moves one: it stayed, built, and Apply
        sent the module an action it refuses."""
        with self._lock:
            options = tuple(self._choice.options)
            if self._choice.value not in options:
                self._choice.value = options[0]  # runs _picked in this thread
            self._build()

    def _build(self) -> None:
        with self._lock:
            name = self._choice.value
            if name == self._built_for:
                return
            self._built_for = name
            for _p, handle in self._widgets:
                handle.remove()
            self._widgets = []
            action = self._actions.get(name)
            if action is None:
                self._params.visible = False
                return
            self._choice.hint = action.doc or None
            snapshot = self._current() if self._current is not None else None
            with self._params:
                self._widgets = [(p, param_widget(self._gui, p,
                                                current_value(snapshot, p.current)))
                                 for p in action.params]
            self._params.visible = bool(self._widgets)

    def submit(self, client: viser.ClientHandle | None) -> None:
        """Apply the picked action with its own Parameters, or nothing and say so. A pick is
        two writes, the action (viser, on its loop) then its Parameters (the pick's callback,
        in viser's threads, where this click runs too), and restrict writes both under the
        lock: the pick read before the widgets paired one action with the other's Parameters
        (module_failure sent with ao_overload's ticked ``active``). Read together, under the
        lock, the pick and the action the Parameters were built for differ until the
        callback has built them."""
        with self._lock:
            name, built = self._choice.value, self._built_for
            typed = [(p, h.value) for p, h in self._widgets] if name == built else None
        if name not in self._actions:
            return
        if typed is None:
            shown = f"still showed {built}'s" if built in self._actions else "had no"
            notify(client, f"{name} not applied",
                   f"the form {shown} Parameters; check {name}'s and Apply again", error=True)
            return
        args = checked_args(client, name, self._actions[name], typed)
        if args is not None:
            self._apply(client, name, args)


def checked_args(client: viser.ClientHandle | None, name: str, action: Action,
                 typed: Sequence[tuple[Param, Any]]) -> dict[str, Any] | None:
    """The arguments of ``action`` (``name``) from what its widgets hold (``typed``: each
    parameter's value), or None after telling ``client``'s page why not (a bad number, a
    check the action table makes)."""
    try:
        args = {p.name: param_value(p, value) for p, value in typed
                if not (blank_allowed(p) and not str(value).strip())}
    except (TypeError, ValueError) as exc:
        notify(client, name, f"bad parameter: {exc}", error=True)
        return None
    try:
        action.check_args(args)
    except CommandError as exc:
        notify(client, f"{name} refused", str(exc), error=True)
        return None
    return args
