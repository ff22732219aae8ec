"""An open rig's Alarm picker offers each page its own drive's alarm list, with the picked
alarm's description as its hint, whichever of its two writers comes last
(app/ui/drive/drive_faults.py ``_show_alarms``): a page's pick (viser's thread pool) and the
dashboard's frame update (its own thread), which takes each page's drive and fieldbus.

The pick's callback read each page's fieldbus, then wrote the lists, unguarded: a frame in
which the page's drive had become the Profinet one (seed 004 ch. 6 numbers 30..33 apart) was
written in between, and the callback wrote the Modbus list over it. The page kept it until
the next frame: 1/30 s on an idle rig, as long as a busy simulation thread takes otherwise.
The test holds the callback between its read and its write, with no frame to put it right.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from form_page import uuid
from pick_race import HOLD_S, HeldProp, SpyLock, inside, off_dashboard, on_dashboard
from test_slave_causes_pick_race import _NoFrames
from viser_page import Page, wait

from app.classroom.roles import Access
from app.rig_config import build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.drive import drive_faults
from app.ui.drive.drive_faults import AlarmForm
from app.ui.drive.drive_options import alarm_options
from app.ui.panels.classroom_rig import ServedRig, serve_rig
from tests.app.test_action_forms_per_page import last_prop
from tests.app.test_classroom_leak import TOKEN
from tests.app.test_drive_alarm_per_page import TWO_BUSES
from tests.app.two_pages import two_pages

FOLLOWING = next(o for o in alarm_options("modbus") if o.startswith("16 "))


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[ServedRig, Page, Page, Any, AlarmForm]]:
    path = tmp_path / "two_buses.toml"
    path.write_text(TWO_BUSES)
    with two_pages(path) as (live, first, second):
        drives = live.dashboard.drives
        assert drives is not None and drives.drive_ids == ["drive", "drive_pn"]
        (form,) = drives.controls._alarms.each()
        assert form.pages is not None
        clients = set(live.server.get_clients())
        wait(lambda: clients <= set(form.pages.buses))  # the dashboard drew both pages
        yield live, first, second, drives, form


def _drawn(live: ServedRig) -> None:
    seq = live.runtime.frame.seq
    wait(lambda: live.dashboard.rendered_seq >= seq)


def test_a_frame_during_a_pick_is_not_undone_by_its_callback(
    served: tuple[ServedRig, Page, Page, Any, AlarmForm],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The pick's callback read the pages' fieldbus (Modbus), a frame with every page on the
    Profinet drive was written, then the callback wrote the Modbus list over it."""
    live, first, second, drives, form = served
    assert form.pages is not None
    alarm = uuid(form.alarm)
    _drawn(live)
    held = HeldProp(form.pages.options, off_dashboard)
    spy = SpyLock(on_dashboard)
    monkeypatch.setattr(form.pages, "options", held)
    monkeypatch.setattr(form, "lock", spy, raising=False)  # the form's lock, if it has one
    written, shown = threading.Event(), drives.controls._show_alarms

    def show(each: AlarmForm) -> None:
        try:
            shown(each)
        finally:
            if off_dashboard() and held.entered.is_set():
                written.set()

    monkeypatch.setattr(drives.controls, "_show_alarms", show)
    held.armed = True
    first.set(alarm, FOLLOWING)
    assert held.entered.wait(HOLD_S), "the pick's callback did not run"
    try:
        drives.select("drive_pn")  # every page's drive: Profinet's list at the next frame
        frames = _NoFrames(live)
        frames.publish()
        seq = live.runtime.frame.seq
        # The dashboard has written that frame, or waits for the callback to write first.
        wait(lambda: spy.waiting.is_set() or live.dashboard.rendered_seq >= seq)
    finally:
        held.release.set()
    try:
        assert written.wait(HOLD_S), "the pick's callback did not finish"
        _drawn(live)
        # No frame comes to put it right: a stale write stays, and this times out. What
        # each page was sent last first (the page may not have received a stale one yet).
        for client_id in live.server.get_clients():
            wait(lambda c=client_id: "31 PROFINET_INIT_1" in (held.sent(c) or ()), timeout=5)
        for page in (first, second):
            wait(lambda page=page: "31 PROFINET_INIT_1" in (last_prop(page, alarm, "options")
                                                           or ()), timeout=5)
    finally:
        frames.end()


def test_a_pick_moved_to_its_drive_s_code_gets_that_code_s_hint(
    served: tuple[ServedRig, Page, Page, Any, AlarmForm],
) -> None:
    """A page's pick of 31 moves to Profinet's 31 when its drive is the Profinet one, in the
    frame update that offers it Profinet's list; that update wrote the hint of the pick before
    the move (none: Profinet has no 31 INTERNAL_COMM_1), until the next frame."""
    live, first, _second, drives, form = served
    alarm = uuid(form.alarm)
    first.set(alarm, "31 INTERNAL_COMM_1")
    wait(lambda: str(last_prop(first, alarm, "hint")).startswith("31 INTERNAL_COMM_1"))
    frames = _NoFrames(live)
    try:
        drives.select("drive_pn")
        frames.publish()
        _drawn(live)
        wait(lambda: (first.updates(alarm) or [None])[-1] == "31 PROFINET_INIT_1",
             timeout=5)
        wait(lambda: str(last_prop(first, alarm, "hint")).startswith("31 PROFINET_INIT_1"),
             timeout=5)
    finally:
        frames.end()


def test_an_instructor_s_pick_during_a_change_of_drive_keeps_its_hint(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With a token and several drives an instructor's Alarms and load rows act on their own
    Drive picker (docs/classroom.md): the list and hint follow that drive's fieldbus at the
    next frame. The hint of a pick (DetailHint, the pick's callback) read the Modbus table, a
    frame with the Profinet drive moved the pick 31 to "31 PROFINET_INIT_1" and wrote its
    hint, then the callback wrote the Modbus table's hint of it (none) over it, for good: the
    frame update writes the hint only when the fieldbus changes."""
    path = tmp_path / "two_buses.toml"
    path.write_text(TWO_BUSES)
    rig = build_rig(load_rig_spec(path), state_dir=None)
    live = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    trainee, instructor = Page(live.port), Page(live.port)
    frames = None
    try:
        clients = wait(lambda: len(live.server.get_clients()) == 2 and live.server.get_clients())
        client_id = sorted(clients)[1]
        assert live.classroom.access.present(client_id, TOKEN)
        live.classroom._promoted(clients[client_id])
        drives = live.dashboard.drives
        assert drives is not None
        form = wait(lambda: drives.controls._alarms.of(client_id))
        assert form.drive is not None and form.hint is not None
        _drawn(live)
        entered, release = threading.Event(), threading.Event()
        held_in: list[threading.Thread] = []
        spy, details = SpyLock(on_dashboard), drive_faults.alarm_details
        monkeypatch.setattr(form, "lock", spy, raising=False)  # the form's lock, if any
        monkeypatch.setattr(form.hint, "_lock", spy, raising=False)

        def held(fieldbus: str) -> Any:
            table = details(fieldbus)
            if off_dashboard() and not entered.is_set():
                held_in.append(threading.current_thread())
                entered.set()  # the table the callback read is fixed, its write is to come
                assert release.wait(HOLD_S), "never released"
            return table

        monkeypatch.setattr(drive_faults, "alarm_details", held)
        instructor.set(uuid(form.alarm), "31 INTERNAL_COMM_1")
        try:
            assert entered.wait(HOLD_S), "the pick's callback did not run"
            frames = _NoFrames(live)
            form.drive.value = "drive_pn"  # the instructor's own Drive picker
            frames.publish()
            seq = live.runtime.frame.seq
            # The frame update has written, or waits for the callback to write first.
            wait(lambda: spy.waiting.is_set() or live.dashboard.rendered_seq >= seq)
        finally:
            release.set()
        wait(lambda: not inside(held_in[0], "refresh"), timeout=HOLD_S)
        _drawn(live)
        assert form.alarm.value == "31 PROFINET_INIT_1"
        # No frame comes to put it right (nor would one): a stale hint stays.
        wait(lambda: str(form.alarm.hint).startswith("31 PROFINET_INIT_1"), timeout=5)
    finally:
        if frames is not None:
            frames.end()
        trainee.close()
        instructor.close()
        live.stop()
