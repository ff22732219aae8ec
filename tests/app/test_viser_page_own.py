"""``Page.own`` finds this page's own widget by a label and an option it offers now: the
options it was created with, or those a later update gave it. Before, only the creation
message counted: an instructor's copy built from a rail the coupler had not numbered yet
(options "1") and given the rail's modules by an update was never found, and the wait failed
after 20 s under load (test_classroom_leak; test_classroom_module_copies.py)."""

from __future__ import annotations

from typing import Any

from test_viser_page_reader import server_sending, viser_frame
from viser_page import Page, wait


def _dropdown(uuid: str, label: str, options: tuple[str, ...]) -> dict[str, Any]:
    return {"type": "GuiDropdownMessage", "uuid": uuid, "value": options[0],
            "props": {"label": label, "options": list(options)}}


def _options(uuid: str, options: tuple[str, ...]) -> dict[str, Any]:
    return {"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"options": list(options)}}


SHARED = _dropdown("shared", "Module", ("1 DB16", "4 AI8D"))
OWN = [_dropdown("own", "Module", ("1",)), _options("own", ("1 DB16", "4 AI8D"))]


def test_an_own_widget_given_its_option_by_an_update_is_found() -> None:
    with server_sending(viser_frame([SHARED])) as other_port, \
            server_sending(viser_frame([SHARED, *OWN])) as port:
        other, page = Page(other_port), Page(port)
        try:
            wait(lambda: len(page.received()) == 3 and other.received())
            assert page.own(other, "Module", "4 AI8D") == "own"
        finally:
            other.close()
            page.close()


def test_an_option_an_update_took_away_is_not_found() -> None:
    """The page's widget offers only what the last update left it: the newer widget no
    longer offers the option, an older one does."""
    took = _options("own", ("1 DB16",))
    older = _dropdown("older", "Module", ("4 AI8D",))
    with server_sending(viser_frame([SHARED])) as other_port, \
            server_sending(viser_frame([SHARED, older, *OWN, took])) as port:
        other, page = Page(other_port), Page(port)
        try:
            wait(lambda: len(page.received()) == 5 and other.received())
            assert page.own(other, "Module", "4 AI8D") == "older"
            assert page.own(other, "Module", "1 DB16") == "own"
        finally:
            other.close()
            page.close()
