"""The drive's Register access and Parameter access buttons (seed 004 ch. 1 "Registri",
"Parametri"): each click reads or writes the register or parameter the page picked, of the
page's drive, and the answer is the line under the boxes, on that page. Both buttons go
through one helper; this pins what each sends and shows."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from test_widgets_synced_panels import DRIVE, Server, _AnsweringSender, frames, turn

from app.ui.drive.drive_panel import DrivePanel


@pytest.mark.parametrize(("box", "pick", "group", "button", "typed", "command", "answer",
                          "shown"), [
    ("Register", "R13 target_velocity", "Register access", "Read register", None,
     ("read_register", {"register": 13}), 500, "R13 target_velocity = 500"),
    ("Register", "R13 target_velocity", "Register access", "Write register", -20,
     ("write_register", {"register": 13, "value": -20}), None,
     "R13 target_velocity = -20 written"),
    ("Parameter", "d1 speed loop proportional gain KP", "Parameter access", "Read param.",
     None, ("read_parameter", {"parameter": "d1"}), 20, "d1 = 20"),
    ("Parameter", "d1 speed loop proportional gain KP", "Parameter access", "Write param.",
     35, ("write_parameter", {"parameter": "d1", "value": 35}), None, "d1 = 35 written"),
])
def test_register_and_parameter_access_send_and_show(
        box: str, pick: str, group: str, button: str, typed: int | None,
        command: tuple[str, dict[str, Any]], answer: Any, shown: str) -> None:
    loop = asyncio.new_event_loop()
    try:
        server, sender = Server(loop, pages=2), _AnsweringSender(answer)
        panel = DrivePanel(server, None, sender, lambda _client: "drive2", {})  # type: ignore[arg-type]
        handles, page, other = server.gui.handles, server.clients[1], server.clients[2]
        handles[box].user(page, pick)
        if typed is not None:
            handles[f"{box} value"].user(page, typed)
        handles[group].user(page, button, click=True)
        turn(loop, server)
        sender.drain()
        assert sender.sent == [("drive2", *command)]
        frames(loop, server, lambda: panel.update(DRIVE), n=1)
        line = panel._result_html._impl.uuid
        assert any(f"<code>{shown}</code>" in c for c in page.sent(line, "content"))
        assert not any("<code>" in c for c in other.sent(line, "content"))  # the asking page's
    finally:
        loop.close()
