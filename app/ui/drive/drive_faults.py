"""The instructor's fault part of the Servo drive tab (a mixin of
:class:`~app.ui.drive.drive_panel.DrivePanel`): the alarm rows (inject / clear an alarm, jam
the load) and, with a token, the form of the other actions that make a fault
(``roles.makes_faults``). With a token both are built per instructor connection, so a trainee's
page never gets them (app/ui/panels/per_client.py; docs/classroom.md). On an open rig the one
Alarm picker is each page's own (a ClientPick): its list and hint are those of the page's own
drive's fieldbus, and Inject / Clear send the clicking page's alarm to its own drive.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import viser

from app.ui.drive.drive_options import alarm_details, alarm_options, leading_int
from app.ui.panels.action_form import ActionForm
from app.ui.panels.client_input import ClientSynced
from app.ui.panels.client_pick import ClientPick, page_ready, same_head
from app.ui.panels.page_prop import PageProp
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import DetailHint, Synced, on_button, set_options, short_label_css
from devices.device import Action
from devices.servo.parameters import FIELDBUS_BY_C9

if TYPE_CHECKING:
    from app.ui.drive.drive_panel import DrivePanel

DRIVE_KIND = "servo"  # the drives' kind in app.classroom.roles
# Every alarm label of any fieldbus (Profinet numbers 30..33 differently, ch. 6): the open
# rig's picker's server-level options, which a page's pick must be one of; each page is
# offered its own drive's (PageProp), so no later message to every page lands over them.
EVERY_ALARM = tuple(dict.fromkeys(label for bus in dict.fromkeys(FIELDBUS_BY_C9.values())
                                  for label in alarm_options(bus)))


@dataclass
class PageAlarms:
    """What each page of an open rig's Alarm picker gets for its own drive: the list and the
    picked alarm's description, and the fieldbus of each page's drive (None: a new page's)."""

    options: PageProp
    hint: PageProp
    buses: dict[int | None, str] = field(default_factory=dict)


@dataclass
class AlarmForm:
    """The instructor's alarm rows of one connection (or the shared ones); ``drive``: its own
    Drive picker (a token and several drives), None when the rows act on the shared one.
    ``alarm``: the shared rows' is a ClientPick (``pages``), a connection's a dropdown."""

    alarm: Any
    ops: Any
    jam: Synced | ClientSynced
    hint: DetailHint | None
    drive: Any = None
    fieldbus: list[str] = field(default_factory=lambda: ["modbus"])  # its drive's, as shown
    pages: PageAlarms | None = None
    # The lists' and hints' writers: a pick (viser's threads) and the frame update. Each reads
    # the fieldbus and the picks and writes under it, or one wrote what it read before the
    # other's write over it: an open rig's page kept that list until the next frame, an
    # instructor's hint for good. Reentrant: the frame update assigns the pick under it,
    # which runs the pick's hint refresh at once in the same thread (viser 1.1.1).
    lock: threading.RLock = field(default_factory=threading.RLock)


class DriveFaults:
    def _own_drive(self: DrivePanel, gui: Any) -> Any:
        """With a token and several drives, an instructor's form gets a Drive picker of its
        own: on the shared Servo drive picker the instructor's pick of the drive to jam or
        alarm went to every trainee's page (docs/classroom.md). None: the shared one."""
        if instructor_for(self._server).shared or len(self._drive_ids) < 2:
            return None
        return gui.add_dropdown("Drive", self._drive_ids, initial_value=self._target(None),
                                hint="the drive this form acts on")

    def _send_to(self: DrivePanel, own: Any, client: viser.ClientHandle | None, action: str,
                 args: dict[str, Any], confirm: bool = False) -> None:
        target = self._target(client) if own is None else str(own.value)
        self._sender.send(client, target, action, args, confirm=confirm)

    def _alarm_form(self: DrivePanel, gui: Any) -> AlarmForm:
        shared = instructor_for(self._server).shared
        with gui.add_folder("Alarms and load"):
            own = self._own_drive(gui)
            fieldbus = [self._fieldbus]
            alarm = gui.add_dropdown("Alarm", EVERY_ALARM if shared
                                     else alarm_options(fieldbus[0]))
            ops = gui.add_button_group("Alarm cause", ("Inject alarm", "Clear alarm"))
            jam = gui.add_checkbox("Load jammed", False, hint="the load cannot move: "
                                   "following error, alarm 16")
        if not shared:  # per client: the narrower label
            gui.add_html(short_label_css([alarm]))
        # The shared form (an open rig) shows each page its own drive's jam
        jammed = Synced if own is not None else self._synced_type()
        jam_box = jammed(self._server, jam, self._sender, lambda c, on: (
            self._send_to(own, c, "jam_load", {"active": bool(on)})))
        if shared:
            # Each page's own: one page's pick of the alarm went to every page, and another
            # page's Inject injected it.
            alarm.hint = alarm_details(fieldbus[0]).get(str(alarm.value))  # a new page's
            pick = ClientPick(self._server, alarm)
            form = AlarmForm(pick, ops, jam_box, None, own, fieldbus, PageAlarms(
                PageProp(self._server, alarm, "options"), PageProp(self._server, alarm, "hint")))
            pick.on_pick(lambda _client, _label: self._show_alarms(form))
        else:
            lock = threading.RLock()
            form = AlarmForm(alarm, ops, jam_box,
                             DetailHint(alarm, lambda: alarm_details(fieldbus[0]), lock), own,
                             fieldbus, lock=lock)
        on_button(ops, lambda e, b: self._send_to(
            own, e.client, "inject_alarm" if b == "Inject alarm" else "clear_alarm",
            {"code": str(leading_int(self._alarm_of(form, e.client_id)))}))
        return form

    @staticmethod
    def _alarm_of(form: AlarmForm, client_id: int | None) -> str:
        """The alarm ``client_id``'s page picked (an open rig's: its own)."""
        if isinstance(form.alarm, ClientPick):
            return form.alarm.value_for(client_id)
        return str(form.alarm.value)

    def _show_alarms(self: DrivePanel, form: AlarmForm) -> None:
        """Each page of an open rig its drive's alarm list and its pick's description; a page
        whose pick its drive's fieldbus does not have moves to the same code ("31
        INTERNAL_COMM_1" -> "31 PROFINET_INIT_1", ch. 6), else to the list's first."""
        pages, pick = form.pages, form.alarm
        if pages is None or not isinstance(pick, ClientPick):
            return
        with form.lock:  # no callback of the form runs from within (set_for sends only)
            buses = dict(pages.buses)

            def bus(client_id: int | None) -> str:
                return buses.get(client_id, buses.get(None, self._fieldbus))

            pages.options.show(lambda client_id: alarm_options(bus(client_id)))
            for client_id, client in self._server.get_clients().items():
                offered = alarm_options(bus(client_id))
                now = pick.value_for(client_id)
                if now not in offered and page_ready(self._server, client):
                    pick.set_for(client, next((o for o in offered if same_head(now, o)),
                                              offered[0]))
            # After the moves: the hint of the pick before one described no alarm of the list
            pages.hint.show(lambda client_id: alarm_details(bus(client_id)).get(
                pick.value_for(client_id)))

    def _fault_form(self: DrivePanel, gui: Any, faults: Mapping[str, Action]) -> ActionForm:
        with gui.add_folder("Drive faults", expand_by_default=False):
            own = self._own_drive(gui)
            return ActionForm(gui, faults, lambda c, name, args: self._send_to(
                own, c, name, args, confirm=True), label="Fault action")

    def _follow_alarm_forms(self: DrivePanel, snap: Mapping[str, Any],
                            devices: Mapping[str, Any],
                            page: Callable[[int | None], Mapping[str, Any]]) -> None:
        """Each alarm form's list, hint and Load jammed box follow its drive: the shared
        drive's (each page its own) or, with its own Drive picker, the picked one's."""
        for form in self._alarms.each():
            if form.pages is not None:  # an open rig's: each page its own drive's fieldbus
                clients = self._server.get_clients()
                form.pages.buses = {c: str(page(c).get("fieldbus", self._fieldbus))
                                    for c in (None, *clients)}
                self._show_alarms(form)
                self._follow(form.jam, lambda s: bool(s.get("jammed")), page)
                continue
            own = snap if form.drive is None else devices.get(str(form.drive.value))
            own = own or {}
            with form.lock:  # the pick's hint refresh reads the fieldbus under it
                bus = str(own.get("fieldbus", form.fieldbus[0]))
                if bus != form.fieldbus[0]:  # Profinet numbers 30..33 differently (ch. 6)
                    form.fieldbus[0] = bus
                    set_options(form.alarm, list(alarm_options(bus)))
                    if form.hint is not None:
                        form.hint.refresh()
            if form.drive is None:
                self._follow(form.jam, lambda s: bool(s.get("jammed")), page)
            else:
                form.jam.follow(bool(own.get("jammed")))
