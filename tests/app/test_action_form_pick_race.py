"""A per-page action form (app/ui/panels/client_action_form.py: the Line tab's slave forms,
the FastCAT's Module I/O, the drive's Drive action) shows each page the Parameters and the
description of the action it has picked, whichever of its two writers comes last: the page's
pick (viser's thread pool) and the frame update (the dashboard thread), which moves a page's
pick its Target does not take to the first one it does and shows that one.

The pick's callback read the page's pick, then showed it, unguarded: a frame update in
between moved the pick (the page picked ``set_dil`` on ``cpx/2``, which takes none: the page's
list was still the device's) and showed the first action ``cpx/2`` takes, then the callback
showed ``set_dil``'s Parameters and description over it. The page's box said one action, its
Parameters and hint another, and nothing put them right (the frame update shows a page only
an action it moves it to). The test holds the callback between its read and its write.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import Any

import pytest
from form_page import uuid
from pick_race import HOLD_S, SpyLock, inside, off_dashboard, on_dashboard
from test_slave_causes_pick_race import _NoFrames
from viser_page import Page, wait

from app.ui.panels import client_action_form
from app.ui.panels.classroom_rig import ServedRig
from app.ui.panels.client_pick import send_to
from tests.app.test_action_forms_per_page import last_prop
from tests.app.test_picks_per_browser import _ids
from tests.app.two_pages import two_pages

MARK = "fr-test-mark"


@pytest.fixture
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages() as pages:
        yield pages


def test_a_frame_during_a_pick_is_not_undone_by_its_callback(
    served: tuple[ServedRig, Page, Page],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    live, first, _second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    _folder, form = controls.forms["cpx"]
    one, _two = _ids(live)
    first.set(uuid(controls.targets["cpx"]), "cpx/2")
    wait(lambda: "force" in form.options(one) and "set_dil" not in form.options(one))
    held_in: list[threading.Thread] = []
    entered, release = threading.Event(), threading.Event()
    sent, spy = client_action_form.send_on, SpyLock(on_dashboard)
    monkeypatch.setattr(form, "_pick_lock", spy, raising=False)  # the form's lock, if any

    def held(client: Any, handle: Any, prop: str, value: Any) -> None:
        if off_dashboard() and not entered.is_set():
            held_in.append(threading.current_thread())
            entered.set()  # what the callback read is fixed, its write is to come
            assert release.wait(HOLD_S), "never released"
        sent(client, handle, prop, value)

    monkeypatch.setattr(client_action_form, "send_on", held)
    frames = None
    first.set(uuid(form.choice), "set_dil")  # in the page's list still, not cpx/2's
    try:
        assert entered.wait(HOLD_S), "the pick's callback did not run"
        frames = _NoFrames(live)
        frames.publish()
        seq = live.runtime.frame.seq
        # The frame update moved the pick, or waits for the callback to write first.
        wait(lambda: spy.waiting.is_set() or live.dashboard.rendered_seq >= seq)
    finally:
        release.set()
    try:
        wait(lambda: not inside(held_in[0], "_picked"), timeout=HOLD_S)
        seq = live.runtime.frame.seq
        wait(lambda: live.dashboard.rendered_seq >= seq)
        moved = form.options(one)[0]
        assert form._pick.value_for(one) == moved
        # What the page got last: everything sent to it before this mark is in
        send_to(live.server.get_clients()[one], uuid(form.button), "hint", MARK)
        wait(lambda: last_prop(first, uuid(form.button), "hint") == MARK)
        for name, folder in form._folders.items():
            assert last_prop(first, uuid(folder), "visible") == (name == moved), name
        assert last_prop(first, uuid(form.choice), "hint") == form._hint(moved)
    finally:
        if frames is not None:
            frames.end()
