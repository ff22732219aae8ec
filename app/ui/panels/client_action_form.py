"""An action form (app/ui/panels/action_form.py) whose pick, parameters and offered actions are
each page's own: the drive's *Drive action* form, the FastCAT's Module I/O and the Line tab's
slave forms (docs/dashboard.md "Several browsers").

The shared :class:`~app.ui.panels.action_form.ActionForm` rebuilds one Parameters folder for
the action picked, so a page's pick switched every page's form, and what one page typed was
every page's and went with another page's Apply. Here every action's parameters are built
once, each action in a folder of its own, hidden but on the pages that picked it; the picker
is a :class:`~app.ui.panels.client_pick.ClientPick`, each box a
:class:`~app.ui.panels.client_form.ClientForm`, and Apply sends the clicking page's pick
with that page's values. The actions a page is offered are its own too
(:meth:`ClientActionForm.restrict_each`: those its own module or Target takes); the
server's list is the whole table and never changes, so no later message to every page can
land over a page's own list (app/ui/panels/page_prop.py). A parameter that names where the
device holds its present value (``Param.current``) is filled from it on the page that picks
the action.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import viser

from app.ui.panels.action_form import (
    MISSING,
    Apply,
    Current,
    blank_allowed,
    checked_args,
    current_value,
    param_widget,
)
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_pick import ClientPick, page_ready, send_on
from app.ui.panels.page_prop import PageProp
from devices.device import Action, CommandError, Param

NONE = "(none)"  # a page whose module or Target takes no action of the form
# The actions each page may pick (None: a new page's), or None when not known yet
NamesFor = Callable[[int | None], Sequence[str] | None]


def box_value(p: Param, now: Any) -> Any:
    """What ``p``'s box shows for the device's present value ``now`` (param_widget's
    initial value for it), or MISSING when the box cannot hold it."""
    try:
        value = p.check(now)
    except CommandError:
        return MISSING
    if blank_allowed(p):
        return "" if value is None else str(value)
    if p.choices:
        return str(value)
    if p.type is bool:
        return bool(value)
    return p.type(value) if p.type in (int, float) else str(value)


class ClientActionForm:
    def __init__(self, server: viser.ViserServer, actions: Mapping[str, Action], apply: Apply,
                 label: str = "Action", current: Current | None = None) -> None:
        """``current``: the target device's latest snapshot, for the parameters that say
        where their present value is (Param.current)."""
        gui = server.gui
        self._server = server
        self._current = current
        self._actions = dict(sorted(actions.items()))
        self._apply = apply
        self._lock = threading.Lock()  # the dashboard thread and the pages' callbacks
        # What a page is shown of its pick: written by its pick's callback and by the frame
        # update that moves a pick its Target does not take. Each reads the pick and writes
        # under it, or the callback showed the pick it read over the one the update had moved
        # it to, for good (the update shows a page only a pick it moves). Reentrant: the
        # update shows a moved pick under it; no callback of the form runs from within.
        self._pick_lock = threading.RLock()
        self._offered: dict[int | None, tuple[str, ...]] = {}
        names = tuple(self._actions) or (NONE,)
        snapshot = current() if current is not None else None
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
                self._fields[name] = [
                    (p, ClientForm(server, param_widget(gui, p, current_value(snapshot,
                                                                              p.current))))
                    for p in action.params]
        self.button = gui.add_button("Apply", disabled=not self._actions)
        self._options = PageProp(server, choice, "options")
        self._disabled = PageProp(server, self.button, "disabled")
        self._pick.on_pick(self._picked)
        self.button.on_click(lambda event: self.submit(event.client))

    def _hint(self, name: str) -> str | None:
        action = self._actions.get(name)
        return (action.doc or None) if action is not None else None

    def _picked(self, client: viser.ClientHandle, _name: str = "") -> None:
        """``client``'s page shows the parameters of its pick, its description and, where a
        parameter says so, the device's present values. The pick is read here, under the
        lock, not taken from the callback's event: the frame update may have moved it."""
        with self._pick_lock:
            name = self._pick.value_for(client.client_id)
            for each, folder in self._folders.items():
                send_on(client, folder, "visible", each == name)
            send_on(client, self._pick.handle, "hint", self._hint(name))
            snapshot = self._current() if self._current is not None else None
            for p, form in self._fields.get(name, ()):
                if p.current:
                    now = current_value(snapshot, p.current)
                    value = MISSING if now is MISSING else box_value(p, now)
                    if value is not MISSING:
                        form.set_for(client, value)

    @property
    def choice(self) -> Any:
        """The action picker."""
        return self._pick.handle

    @property
    def handles(self) -> tuple[Any, ...]:
        """The form's own widgets: picker, each action's Parameters folder, Apply."""
        return (self._pick.handle, *self._folders.values(), self.button)

    def options(self, client_id: int | None = None) -> tuple[str, ...]:
        """What ``client_id``'s page is offered (None: a new page)."""
        with self._lock:
            offered = self._offered.get(client_id, self._offered.get(None))
        return offered if offered is not None else tuple(self._actions) or (NONE,)

    def picked(self, client_id: int | None) -> str:
        """``client_id``'s pick among what it is offered (a pick its page has not been moved
        off yet counts as the first it is offered)."""
        offered = self.options(client_id)
        name = self._pick.value_for(client_id)
        return name if name in offered else offered[0]

    def field(self, action: str, param: str) -> ClientForm:
        """The box of ``action``'s parameter ``param``."""
        return next(form for p, form in self._fields[action] if p.name == param)

    def restrict_each(self, names_for: NamesFor) -> None:
        """Offer each page the actions ``names_for(client_id)`` (the dashboard thread): its
        own module's or Target's. A page whose pick is not offered moves to the first one
        that is, as the shared form's picker did."""
        clients = self._server.get_clients()
        with self._lock:
            for client_id in (None, *clients):
                names = names_for(client_id)
                if names is not None:
                    wanted = set(names)
                    self._offered[client_id] = tuple(
                        n for n in self._actions if n in wanted) or (NONE,)
            for gone in set(self._offered) - set(clients) - {None}:
                del self._offered[gone]
        self._options.show(self.options)
        self._disabled.show(lambda client_id: self.options(client_id) == (NONE,))
        for client_id, client in clients.items():
            if not page_ready(self._server, client):
                continue  # the options go first (PageProp.show waits for it too)
            offered = self.options(client_id)
            with self._pick_lock:
                if self._pick.value_for(client_id) not in offered:
                    self._pick.set_for(client, offered[0])
                    self._picked(client)

    def submit(self, client: viser.ClientHandle | None) -> None:
        """Apply what ``client``'s page picked, with the values its boxes hold (a new page's
        when None)."""
        name = self.picked(getattr(client, "client_id", None))
        action = self._actions.get(name)
        if action is None:
            return
        typed = [(p, form.value_of(client)) for p, form in self._fields.get(name, ())]
        args = checked_args(client, name, action, typed)
        if args is not None:
            self._apply(client, name, args)
