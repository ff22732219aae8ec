"""InstructorHtml.show_each (app/ui/panels/per_client.py): each instructor copy the causes of
its page's drive pick. viser lets a leaving page go (it leaves ``get_clients()``) and marks its
widgets removed before the disconnect callback forgets the copy (Part.each, docs/classroom.md);
a frame in between assigned the removed copy's content, viser's RuntimeError "Cannot assign to
'content' on a removed GuiHtmlHandle", which ended the Servo drive tab's frame update."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from app.classroom.roles import Access
from app.ui.panels.per_client import Instructor, InstructorHtml


class _Html:
    """A client-level HTML handle: viser 1.1.1 refuses a write once it is removed."""

    def __init__(self) -> None:
        self.removed = False
        self._content = ""

    @property
    def content(self) -> str:
        return self._content

    @content.setter
    def content(self, value: str) -> None:
        if self.removed:
            raise RuntimeError("Cannot assign to 'content' on a removed GuiHtmlHandle.")
        self._content = value


class _Server:
    def __init__(self) -> None:
        self.clients: dict[int, Any] = {}
        self.gui = SimpleNamespace(_get_container_uuid=lambda: "root")

    def get_clients(self) -> dict[int, Any]:
        return dict(self.clients)

    def on_client_disconnect(self, fn: Any) -> None:
        return None


def test_a_page_that_left_gets_no_content_before_its_disconnect_callback() -> None:
    server = _Server()
    instructor = Instructor(server, Access("token"))  # type: ignore[arg-type]
    html = InstructorHtml(instructor)
    here, gone = _Html(), _Html()
    server.clients = {1: object()}
    html._part._built.update({1: here, 2: gone})  # two instructor pages' copies
    gone.removed = True  # page 2 left; its disconnect callback has not run yet
    html.show_each(lambda client_id: f"jam on drive {client_id}")
    assert here.content == "jam on drive 1" and gone.content == ""
