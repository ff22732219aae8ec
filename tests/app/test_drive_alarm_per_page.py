"""The drive's Alarm picker (inject / clear an alarm) is each page's own on an open rig
(docs/dashboard.md "Several browsers"): page A's pick moves nothing on page B, B's *Inject
alarm* injects B's own pick into B's own drive, and each page's hint describes its own pick.
Before, the picker was one for every page: A's pick of alarm 16 showed on B's page and B's
Inject injected it. Two websocket connections stand in for the browsers."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from form_page import uuid
from viser_page import Page, wait

from app.ui.drive.drive_options import alarm_options
from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_action_forms_per_page import last_prop
from tests.app.test_forms_per_browser import _frames
from tests.app.two_pages import two_pages


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages() as pages:
        yield pages


def _alarms(live: ServedRig, drive: str) -> list[Any]:
    return list(live.runtime.submit(
        lambda: live.rig.device(drive).snapshot()["injected"]).result(timeout=10))


def test_the_alarm_pick_and_inject_are_each_page_s_own(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    drives = live.dashboard.drives
    assert drives is not None
    (form,) = drives.controls._alarms.each()
    alarm, ops = uuid(form.alarm), uuid(form.ops)
    following = next(o for o in alarm_options("modbus") if o.startswith("16 "))
    first.set(alarm, following)
    wait(lambda: str(last_prop(first, alarm, "hint")).startswith("16 FOLLOWING_ERROR: "))
    _frames(live)
    assert following not in second.updates(alarm)
    assert not str(last_prop(second, alarm, "hint")).startswith("16 ")
    drive = drives.drive_ids[0]  # both pages' drive (no page picked another)
    second.set(ops, "Inject alarm")
    wait(lambda: _alarms(live, drive))
    assert [a.get("code") for a in _alarms(live, drive)] == [1]  # B's: the list's first
    second.set(ops, "Clear alarm")
    wait(lambda: not _alarms(live, drive))
    first.set(ops, "Inject alarm")
    wait(lambda: _alarms(live, drive))
    assert [a.get("code") for a in _alarms(live, drive)] == [16]
    first.set(ops, "Clear alarm")
    wait(lambda: not _alarms(live, drive))
