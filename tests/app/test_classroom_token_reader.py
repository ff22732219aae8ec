"""The token reader (a worker thread started when a page connects, classroom_access.py)
puts its URL snippet on the page only while the page is there. Under load the thread starts
late: a page that had already left got the snippet queued on its closed connection (viser:
"Queued a GuiHtmlMessage on a closed connection ... it will never be delivered"), which
failed test_classroom_redraw's test_a_page_that_left_gets_no_update_before_its_disconnect_
callback (UserWarning as an error) in a loaded batch run."""

from __future__ import annotations

import pytest
from test_classroom_leak import TOKEN, Page, _wait

from app.classroom.roles import Access
from app.screenshots import free_port
from app.ui.panels.classroom_access import read_browser_token


@pytest.mark.filterwarnings("error::UserWarning")
def test_a_page_that_left_gets_no_snippet() -> None:
    import viser

    server = viser.ViserServer(port=free_port(), verbose=False)
    try:
        page = Page(server.get_port())
        client = next(iter(_wait(lambda: server.get_clients()).values()))
        page.close()
        _wait(lambda: not server.get_clients())
        promoted: list[int] = []

        def alive() -> bool:
            return client.client_id in server.get_clients()

        assert not read_browser_token(client, Access(TOKEN), lambda c: promoted.append(1),
                                      wait_s=1.0, alive=alive)
        assert promoted == []
    finally:
        server.stop()
