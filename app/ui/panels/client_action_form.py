"""An action form (app/ui/panels/action_form.py) whose pick and parameters are each page's own:
the drive's *Drive action* form (docs/dashboard.md "Several browsers").

The shared :class:`~app.ui.panels.action_form.ActionForm` rebuilds one Parameters folder for
the action picked, so a page's pick switched every page's form, and what one page typed was
every page's and went with another page's Apply. Here every action's parameters are built
once, each action in a folder of its own, hidden but on the pages that picked it; the picker
is a :class:`~app.ui.panels.client_pick.ClientPick`, each box a
:class:`~app.ui.panels.client_form.ClientForm`, and Apply sends the clicking page's pick
with that page's values. For a fixed table of actions whose parameters start at their
defaults (no ``Param.current``, no ``restrict``), which the drive's is.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import viser

from app.ui.panels.action_form import Apply, checked_args, param_widget
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_pick import ClientPick, send_on
from devices.device import Action, Param


class ClientActionForm:
    def __init__(self, server: viser.ViserServer, actions: Mapping[str, Action], apply: Apply,
                 label: str = "Action") -> None:
        gui = server.gui
        self._actions = dict(sorted(actions.items()))
        self._apply = apply
        names = tuple(self._actions) or ("(none)",)
        choice = gui.add_dropdown(label, names)
        choice.hint = self._hint(names[0])  # a new page's
        self._pick = ClientPick(server, choice)
        self._folders: dict[str, Any] = {}
        self._fields: dict[str, list[tuple[Param, ClientForm]]] = {}
        for name, action in self._actions.items():
            if not action.params:
                continue
            self._folders[name] = folder = gui.add_folder(
                "Parameters", expand_by_default=True, visible=name == names[0])
            with folder:
                self._fields[name] = [(p, ClientForm(server, param_widget(gui, p)))
                                      for p in action.params]
        button = gui.add_button("Apply", disabled=not self._actions)
        self._pick.on_pick(self._picked)
        button.on_click(lambda event: self.submit(event.client))

    def _hint(self, name: str) -> str | None:
        action = self._actions.get(name)
        return (action.doc or None) if action is not None else None

    def _picked(self, client: viser.ClientHandle, name: str) -> None:
        """``client``'s page shows the parameters of its pick, and its description."""
        for each, folder in self._folders.items():
            send_on(client, folder, "visible", each == name)
        send_on(client, self._pick.handle, "hint", self._hint(name))

    @property
    def choice(self) -> Any:
        """The action picker."""
        return self._pick.handle

    def options(self) -> tuple[str, ...]:
        return self._pick.options

    def field(self, action: str, param: str) -> ClientForm:
        """The box of ``action``'s parameter ``param``."""
        return next(form for p, form in self._fields[action] if p.name == param)

    def submit(self, client: viser.ClientHandle | None) -> None:
        """Apply what ``client``'s page picked, with the values its boxes hold (a new page's
        when None)."""
        name = self._pick.value_for(getattr(client, "client_id", None))
        action = self._actions.get(name)
        if action is None:
            return
        typed = [(p, form.value_of(client)) for p, form in self._fields.get(name, ())]
        args = checked_args(client, name, action, typed)
        if args is not None:
            self._apply(client, name, args)
