"""One page (a websocket, tests/app/viser_page.py) filling a per-page action form
(app/ui/panels/client_action_form.py) of a served rig as a browser does: it picks the action,
fills the boxes and presses Apply."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from viser_page import Page, wait

from app.screenshots import ServedRig
from app.ui.panels.client_action_form import ClientActionForm


@contextmanager
def page_on(live: ServedRig) -> Iterator[Page]:
    before = set(live.server.get_clients())
    page = Page(int(live.url.rsplit(":", 1)[1]))
    try:
        wait(lambda: set(live.server.get_clients()) - before)
        time.sleep(0.3)  # the replay of the shared elements
        yield page
    finally:
        page.close()


def uuid(handle: Any) -> str:
    return str(getattr(handle, "handle", handle)._impl.uuid)


def fill(page: Page, form: ClientActionForm, action: str, **values: Any) -> None:
    """``page`` picks ``action`` and types ``values`` into its boxes (one message each 50 ms
    window, as a browser's sender)."""
    page.set(uuid(form.choice), action)
    time.sleep(0.1)
    for name, value in values.items():
        page.set(uuid(form.field(action, name)), value)
        time.sleep(0.1)


def press(page: Page, form: ClientActionForm) -> None:
    page.set(uuid(form.button), True)
