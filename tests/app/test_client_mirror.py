"""ClientMirror (app/ui/panels/client_input.py): a form field filled from each page's model
value (c9 / c7, the CANopen master's Heartbeat). What one page types is that page's: viser
stores it as the widget's value, which is what a new page is sent and what a page the
mirror has not filled yet read. A page that typed a heartbeat period put it in every page
opening meanwhile, and in the Set heartbeat of a page not yet filled."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from types import SimpleNamespace

import pytest
from test_client_form import _Server
from viser._messages import GuiUpdateMessage

from app.ui.panels import client_input
from app.ui.panels.client_input import ClientMirror
from app.ui.panels.decoder import _Field


@pytest.fixture
def loop() -> Iterator[asyncio.AbstractEventLoop]:
    loop = asyncio.new_event_loop()
    yield loop
    loop.close()


def test_a_typed_value_is_the_typing_page_s_only(
        loop: asyncio.AbstractEventLoop, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(client_input, "page_ready", lambda server, client: False)
    server = _Server(loop)
    handle = SimpleNamespace(_impl=SimpleNamespace(uuid="hb", value=0, sync_cb=1))
    mirror = ClientMirror(server, handle)  # type: ignore[arg-type]
    mirror.follow_each(lambda client_id: 250)  # the node's 0x1017; no page ready yet
    handle._impl.value = 700  # viser stored page 1's message ...
    assert mirror.value_for(2) == 250  # ... a read for page 2 meanwhile
    server._websock_server.message(1, GuiUpdateMessage("hb", {"value": 700}))
    assert mirror.value_for(1) == 700 and mirror.value_for(2) == 250
    assert handle._impl.value == 250  # what a new page is sent: the model's


def test_the_codes_tab_fields_keep_a_typed_code_off_new_pages(
        loop: asyncio.AbstractEventLoop, monkeypatch: pytest.MonkeyPatch) -> None:
    """The Codes tab's Code box and Reported pick (decoder._Field, a ClientMirror telling the
    panel of each change): a code one page typed was what every page opening next was sent."""
    monkeypatch.setattr(client_input, "page_ready", lambda server, client: False)
    server = _Server(loop)
    handle = SimpleNamespace(_impl=SimpleNamespace(uuid="code", value="", sync_cb=1))
    heard: list[tuple[int, str]] = []
    field = _Field(server, handle,  # type: ignore[arg-type]
                   lambda client_id, value: heard.append((client_id, value)))
    field.follow_each(lambda client_id: "0x0016")  # the rig's newest code, for new pages
    handle._impl.value = "0x001B"  # viser stored page 1's message
    server._websock_server.message(1, GuiUpdateMessage("code", {"value": "0x001B"}))
    assert heard == [(1, "0x001B")]
    assert handle._impl.value == "0x0016"  # what a new page is sent: the rig's newest
