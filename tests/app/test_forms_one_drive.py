"""On a rig with one drive and one dictionary (no picker), what a page types and reads is its
own as well (docs/dashboard.md "Several browsers", docs/classroom.md): the drive's Register
box and the answer line under it, the CANopen master's NMT command, SDO object and SDO value
boxes, the Drive action form, the Objects tab's boxes. Before, they were each page's own only
where a picker made them so (several drives, several dictionaries); on a one-drive rig a
trainee typing a register number changed every classmate's box and one page's read result
showed on every page. Two websocket connections stand in for the browsers
(tests/app/test_forms_per_browser.py, whose register test runs on this rig as well)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest

from app.ui.panels.classroom_rig import ServedRig
from tests.app.test_classroom_leak import Page, _wait
from tests.app.test_forms_per_browser import _frames, object_read
from tests.app.test_picks_per_browser import _widget
from tests.app.two_pages import one_drive_pages


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ServedRig, Page, Page]]:
    with one_drive_pages(tmp_path_factory.mktemp("rig")) as pages:
        yield pages


def test_the_rig_has_one_drive_and_its_canopen_master(
        served: tuple[ServedRig, Page, Page]) -> None:
    drives = served[0].dashboard.drives
    assert drives is not None and drives.drive_ids == ["drive"] and drives.master is not None
    objects = served[0].dashboard.objects
    assert objects is not None and objects.device_id == "fastcat"


def test_an_object_read_on_one_page_fills_that_page_s_boxes_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    objects = live.dashboard.objects
    assert objects is not None and objects.device_id == "fastcat"
    value, address = object_read(live, first, "0x1000:0"), _widget(first, "Object", None)
    assert second.updates(value) == [] and second.updates(address) == []


def _sent_frames(live: ServedRig) -> int:
    drives = live.dashboard.drives
    assert drives is not None and drives.master is not None
    return drives.master.sent


def _node(live: ServedRig, key: str) -> Any:
    """The node's ``key`` once the frames sent so far have been through it (the paused rig
    stepped 50 ms)."""
    live.runtime.advance(50_000).result(10)
    node = live.rig.devices["drive-can"]
    return live.runtime.submit(lambda: node.snapshot()[key]).result(10)


def test_the_sdo_boxes_and_the_nmt_command_are_each_page_s_own(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    obj, value = _widget(first, "SDO object", None), _widget(first, "SDO value", None)
    nmt = _widget(first, "NMT command", None)
    first.set(obj, "0x1017:0")
    time.sleep(0.1)  # the page's sender: one message each 50 ms window
    first.set(value, "300")
    time.sleep(0.1)
    first.set(nmt, "Stop (0x02)")
    time.sleep(0.1)
    sent = _sent_frames(live)
    # B downloads what its own boxes show (0x6041:0 = 0, read only): not A's 0x1017 = 300
    second.set(_widget(second, "SDO", "Download"), "Download")
    _wait(lambda: _sent_frames(live) > sent)
    _frames(live)
    assert _node(live, "heartbeat_ms") == 0
    assert second.updates(obj) == [] and second.updates(value) == []
    assert second.updates(nmt) == []
    # A's Download writes A's 0x1017 = 300
    first.set(_widget(first, "SDO", "Download"), "Download")
    _wait(lambda: _node(live, "heartbeat_ms") == 300)
    # B's Send NMT sends B's command (Start, the initial): the node stays operational...
    nmt_button = _widget(second, "Send NMT", None)
    second.set(nmt_button, True)
    _wait(lambda: _sent_frames(live) > sent + 2)
    assert _node(live, "nmt") != "Stopped"
    first.set(nmt_button, True)  # ... A's stops it
    _wait(lambda: _node(live, "nmt") == "Stopped")


def _last(page: Page, label: str) -> str:
    """The uuid of the newest widget labelled ``label`` the page got."""
    def find() -> str | None:
        for m in reversed(page.received()):
            if (m.get("props") or {}).get("label") == label:
                return str(m["uuid"])
        return None
    return str(_wait(find))


def _after(page: Page, uuid: str, label: str) -> str:
    """The uuid of the first widget labelled ``label`` the page got after widget ``uuid``."""
    messages = page.received()
    start = next(k for k, m in enumerate(messages) if m.get("uuid") == uuid)
    return next(str(m["uuid"]) for m in messages[start:]
                if (m.get("props") or {}).get("label") == label)


def test_the_drive_action_form_is_each_page_s_own(
        served: tuple[ServedRig, Page, Page]) -> None:
    """A picks write_register and fills it; B's picker and boxes are unchanged, B's Apply
    applies B's own pick (the first action, alarm_reset), A's Apply A's."""
    live, first, second = served
    drives = live.dashboard.drives
    assert drives is not None
    form = drives.controls._form
    applied: list[tuple[int, str, dict[str, Any]]] = []
    apply = form._apply

    def recorded(client: Any, name: str, args: dict[str, Any]) -> None:
        applied.append((client.client_id, name, dict(args)))
        apply(client, name, args)

    form._apply = recorded  # type: ignore[method-assign]
    first_id, second_id = sorted(live.server.get_clients())
    choice = _widget(first, "Drive action", "write_register")
    first.set(choice, "write_register")
    time.sleep(0.3)  # the old form rebuilt its parameters for the pick
    register, value = _last(first, "register"), _last(first, "value")
    first.set(register, 13)
    time.sleep(0.1)
    first.set(value, 777)
    time.sleep(0.1)
    _frames(live)
    assert second.updates(choice) == [] and second.updates(register) == []
    assert second.updates(value) == []
    button = _after(second, choice, "Apply")
    second.set(button, True)
    _wait(lambda: applied)
    assert applied == [(second_id, form.options()[0], {})]
    first.set(button, True)
    _wait(lambda: len(applied) == 2)
    assert applied[1] == (first_id, "write_register", {"register": 13, "value": 777})


def test_the_fieldbus_boxes_are_each_page_s_own(
        served: tuple[ServedRig, Page, Page]) -> None:
    """c9 and c7 are filled from the drive (what it latched at power-up) and typed before
    "Write c9 and c7": what A types is A's."""
    live, first, second = served
    node = _widget(first, "Node (c7)", None)
    first.set(node, 42)
    time.sleep(0.1)
    _frames(live)
    assert 42 not in second.updates(node)
    drives = live.dashboard.drives
    assert drives is not None
    assert drives.controls._mirrors["c7"].handle.value == 2  # what a new page is sent
