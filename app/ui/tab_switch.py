"""Opening a tab of the left panel in every connected browser, for a scenario's focus step.

viser has no server-side way to pick a browser's tab. As the classroom's token hand-over does
(app/ui/panels/classroom_access.py), a per-client snippet does it in the page: an invisible
image whose failed load presses the tab of that label, the leftmost one of that name (the
control panel also has a "Line" tab). viser's docked tabs answer the pointer events of a press
(they can be dragged), not a bare ``click()``. The image then marks itself done
(``data-done``, which the screenshot tool waits for). Per client: a browser that connects
later keeps its own tab.
"""

from __future__ import annotations

import html
import itertools
import json
import logging
from collections.abc import Sequence
from typing import Any

import viser

logger = logging.getLogger(__name__)

SNIPPET_ID = "fr-tab-switch"
CLICK_JS = (
    "try{{var L={label};var t=[].slice.call(document.querySelectorAll('[role=tab]'))"
    ".filter(function(e){{return e.textContent.trim()===L;}});"
    "t.sort(function(a,b){{return a.getBoundingClientRect().left"
    "-b.getBoundingClientRect().left;}});"
    "if(t.length&&t[0].getAttribute('aria-selected')!=='true'){{"
    "['pointerdown','mousedown','pointerup','mouseup','click'].forEach(function(k){{"
    "t[0].dispatchEvent(new PointerEvent(k,{{bubbles:true,cancelable:true,button:0,"
    "isPrimary:true,pointerType:'mouse'}}));}});}}}}catch(e){{}}this.dataset.done='1';")


def tab_for(device: str, *, master: str | None, coupler: str | None, line: Sequence[str],
            drives: Sequence[str]) -> str | None:
    """The left panel's tab that shows ``device``: the master's Line tab (only with the line),
    the Slave tab of a slave the line draws (the drive's EtherCAT side too), the coupler's
    State tab, a drive's Drive tab; None for anything else."""
    if device == master:
        return "Line"
    if device == coupler:
        return "State"
    if device in line:
        return "Slave"
    if device in drives:
        return "Drive"
    return None


def snippet(label: str, serial: int) -> str:
    """The image that opens tab ``label``; ``serial`` makes each one a new element."""
    script = html.escape(CLICK_JS.format(label=json.dumps(label)), quote=True)
    return (f'<img id="{SNIPPET_ID}" data-n="{serial}" src="data:," alt="" '
            f'style="display:none" onerror="{script}">')


class TabSwitcher:
    def __init__(self, server: viser.ViserServer) -> None:
        self._server = server
        self._serial = itertools.count(1)
        self._shown: dict[int, Any] = {}  # client id -> its last snippet

    def open(self, label: str) -> None:
        """Open tab ``label`` in every connected browser (the previous snippet removed)."""
        serial = next(self._serial)
        clients = self._server.get_clients()
        for client_id in set(self._shown) - set(clients):
            self._shown.pop(client_id)
        for client_id, client in clients.items():
            try:
                old = self._shown.pop(client_id, None)
                if old is not None:
                    old.remove()
                self._shown[client_id] = client.gui.add_html(snippet(label, serial))
            except Exception:  # a browser that just left
                logger.debug("tab switch for client %s failed", client_id, exc_info=True)
