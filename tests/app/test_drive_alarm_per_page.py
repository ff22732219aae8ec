"""The drive's Alarm picker (inject / clear an alarm) is each page's own on an open rig
(docs/dashboard.md "Several browsers"): page A's pick moves nothing on page B, B's *Inject
alarm* injects B's own pick into B's own drive, and each page's hint describes its own pick.
Before, the picker was one for every page: A's pick of alarm 16 showed on B's page and B's
Inject injected it. Two websocket connections stand in for the browsers."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from form_page import uuid
from viser_page import Page, wait

from app.ui.drive.drive_options import alarm_options
from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_action_forms_per_page import last_prop
from tests.app.test_forms_per_browser import _frames
from tests.app.test_picks_per_browser import _widget
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


TWO_BUSES = """
[rig]
name = "a Modbus drive and a Profinet drive"
seed = 1
step_ms = 1

[[servo]]
id = "drive"
fieldbus = "modbus"
node_id = 1

[[servo]]
id = "drive_pn"
fieldbus = "profinet"
node_id = 2
"""


def test_each_page_is_offered_its_own_drive_s_alarms(tmp_path: Path) -> None:
    """Profinet numbers 30..33 differently (seed 004 ch. 6): the page that picked the Profinet
    drive is offered its table and its pick of 31 moves to the same code there, the other
    page keeps the Modbus table."""
    path = tmp_path / "two_buses.toml"
    path.write_text(TWO_BUSES)
    with two_pages(path) as (live, first, second):
        drives = live.dashboard.drives
        assert drives is not None and drives.drive_ids == ["drive", "drive_pn"]
        (form,) = drives.controls._alarms.each()
        alarm = uuid(form.alarm)
        first.set(alarm, "31 INTERNAL_COMM_1")
        time.sleep(0.2)
        first.set(_widget(first, "Servo drive", "drive_pn"), "drive_pn")
        wait(lambda: "31 PROFINET_INIT_1" in (last_prop(first, alarm, "options") or ()))
        wait(lambda: first.updates(alarm) and first.updates(alarm)[-1] == "31 PROFINET_INIT_1")
        _frames(live)
        assert "31 INTERNAL_COMM_1" in last_prop(second, alarm, "options")
        assert "31 PROFINET_INIT_1" not in last_prop(second, alarm, "options")
        first.set(uuid(form.ops), "Inject alarm")
        wait(lambda: _alarms(live, "drive_pn"))
        assert [a.get("code") for a in _alarms(live, "drive_pn")] == [31]
        assert _alarms(live, "drive") == []
