"""How a browser becomes the instructor: the token in the URL (``?token=...``) or typed in.

viser gives the server no page URL, so the page hands the token over itself: a per-client HTML
snippet copies ``token`` from the page's query into the browser's localStorage, where the
server reads it (``client.local_storage``). A token typed into the small form is stored there
too, so a reload keeps the role. Either way the server compares it with the rig's token
(:class:`app.classroom.roles.Access`); nothing the browser claims is trusted beyond that.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import viser

from app.classroom.roles import Access, Role
from app.ui.commands import notify

logger = logging.getLogger(__name__)

TOKEN_KEY = "fieldrig-token"  # viser prefixes its localStorage keys ("viser-user:")
URL_POLL_S = 0.25
URL_WAIT_S = 30.0  # a loaded machine may take many seconds to render the page
# Runs when the (broken, invisible) image fails to load: copies ?token=... into localStorage.
URL_SNIPPET = (
    '<img src="data:," alt="" style="display:none" onerror="try{var t=new URLSearchParams('
    "window.location.search).get('token');if(t){localStorage.setItem('viser-user:"
    + TOKEN_KEY + "',t);}}catch(e){}\">")

Promoted = Callable[[viser.ClientHandle], None]


class TokenForm:
    """The per-client token form of one trainee connection (built inside a container)."""

    def __init__(self, client: viser.ClientHandle, access: Access, promoted: Promoted) -> None:
        self._client, self._access, self._promoted = client, access, promoted
        gui = client.gui
        self._folder = gui.add_folder("Instructor login", expand_by_default=False)
        with self._folder:
            self._token = gui.add_text("Token", "", hint="the instructor token printed when "
                                                         "the server started")
            button = gui.add_button("Log in as instructor", icon=viser.Icon.KEY)
        button.on_click(lambda _event: self.submit(str(self._token.value)))

    def submit(self, token: str) -> bool:
        if not self._access.present(self._client.client_id, token):
            logger.warning("connection %s: wrong instructor token", self._client.client_id)
            notify(self._client, "Instructor login", "wrong token", error=True)
            return False
        try:
            self._client.local_storage.set_item(TOKEN_KEY, token.strip())
        except Exception:
            logger.debug("could not remember the token in the browser", exc_info=True)
        self._promoted(self._client)
        return True

    def remove(self) -> None:
        self._folder.remove()


def read_browser_token(client: viser.ClientHandle, access: Access, promoted: Promoted,
                       wait_s: float = URL_WAIT_S,
                       alive: Callable[[], bool] = lambda: True) -> bool:
    """Blocking (run it in a worker thread): put the URL snippet on the page, then look for
    a token in the browser's storage for up to ``wait_s``; promote on the right one.
    ``alive``: False once the browser or the server is gone (stop asking)."""
    if not alive():  # the thread starts late under load: the page may have left meanwhile
        return False
    snippet = client.gui.add_html(URL_SNIPPET)
    deadline = time.monotonic() + wait_s
    try:
        while time.monotonic() < deadline and alive():
            try:
                token = client.local_storage.get_item(TOKEN_KEY, timeout=wait_s)
            except (RuntimeError, TimeoutError):
                return False  # the browser went away or keeps no storage
            if token:
                if access.role(client.client_id) is Role.INSTRUCTOR:
                    return True
                if access.present(client.client_id, token):
                    promoted(client)
                    return True
                logger.warning("connection %s: wrong instructor token in the URL",
                               client.client_id)
                client.local_storage.remove_item(TOKEN_KEY)
                return False
            time.sleep(URL_POLL_S)
        return False
    finally:
        try:
            snippet.remove()
        except Exception:
            logger.debug("snippet already gone", exc_info=True)
