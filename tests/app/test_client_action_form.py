"""The drive's Drive action form (app/ui/panels/client_action_form.py): each page picks its
action, sees its parameters and fills them; Apply sends the clicking page's pick and values
(docs/dashboard.md "Several browsers"). The fake viser of tests/app/fake_viser.py, two
pages."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import Any

import pytest
from test_widgets_synced_panels import Server, turn

from app.ui.panels.client_action_form import ClientActionForm
from devices.servo.actions import ACTIONS

Applied = list[tuple[int | None, str, dict[str, Any]]]


@pytest.fixture
def form() -> Iterator[tuple[Server, ClientActionForm, Applied]]:
    loop = asyncio.new_event_loop()
    server = Server(loop, pages=2)
    applied: Applied = []
    form = ClientActionForm(
        server, ACTIONS,  # type: ignore[arg-type]
        lambda client, name, args: applied.append((client.client_id, name, args)),
        label="Drive action")
    try:
        yield server, form, applied
    finally:
        loop.close()


def _folder(form: ClientActionForm, action: str) -> str:
    return str(form._folders[action]._impl.uuid)


def test_each_page_sees_its_own_pick_s_parameters(
        form: tuple[Server, ClientActionForm, Applied]) -> None:
    server, actions, _ = form
    page, other = server.clients[1], server.clients[2]
    actions.choice.user(page, "read_object")
    turn(server.get_event_loop(), server)
    assert page.sent(_folder(actions, "read_object"), "visible") == [True]
    assert page.sent(_folder(actions, "move"), "visible") == [False]
    assert page.sent(actions.choice._impl.uuid, "hint")[-1] == ACTIONS["read_object"].doc
    assert other.messages == []  # nothing of page 1's pick on page 2
    assert actions.choice.sent == []  # nor for every page


def test_apply_sends_the_clicking_page_s_pick_and_values(
        form: tuple[Server, ClientActionForm, Applied]) -> None:
    server, actions, applied = form
    page, other = server.clients[1], server.clients[2]
    actions.choice.user(page, "read_object")
    actions.field("read_object", "index").handle.user(page, 0x6041)
    actions.submit(other)  # page 2 picked nothing: the first action, no parameters
    actions.submit(page)  # the optional sub with its default is sent (as ActionForm did)
    assert applied == [(2, actions.options()[0], {}),
                       (1, "read_object", {"index": 0x6041, "sub": 0})]


def test_a_bad_value_is_told_to_the_clicking_page_only(
        form: tuple[Server, ClientActionForm, Applied]) -> None:
    server, actions, applied = form
    page, other = server.clients[1], server.clients[2]
    actions.choice.user(page, "write_register")
    actions.field("write_register", "register").handle.user(page, 9999)
    actions.submit(page)
    assert applied == [] and page.notices and page.notices[0][0] == "write_register refused"
    assert other.notices == []


def test_each_page_is_offered_its_own_actions(
        form: tuple[Server, ClientActionForm, Applied]) -> None:
    """restrict_each: page 1 is offered read_object alone and its pick moves there; page 2
    nothing ("(none)", Apply disabled), and its Apply sends nothing."""
    server, actions, applied = form
    page, other = server.clients[1], server.clients[2]
    offered = {1: ["read_object", "not_an_action"], 2: []}
    actions.restrict_each(lambda client_id: offered.get(client_id))  # type: ignore[arg-type]
    uuid = actions.choice._impl.uuid
    assert page.sent(uuid, "options") == [("read_object",)]
    assert page.sent(uuid, "value") == ["read_object"]  # moved to what it is offered
    assert page.sent(_folder(actions, "read_object"), "visible") == [True]
    assert other.sent(uuid, "options") == [("(none)",)]
    assert other.sent(actions.button._impl.uuid, "disabled") == [True]
    assert actions.options(None) == tuple(sorted(ACTIONS))  # a new page: not known yet
    actions.submit(other)
    actions.submit(page)
    assert applied == [(1, "read_object", {"index": 0, "sub": 0})]
