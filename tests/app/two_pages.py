"""An open rig served paused with two websocket pages on it, the stand-ins for two browsers of
the per-page tests (docs/dashboard.md "Several browsers")."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from viser_page import Page, wait

from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.panels.classroom_rig import ServedRig, serve_rig


@contextmanager
def two_pages(path: Path = DEFAULT_RIG,
              prepare: Callable[[ServedRig], None] | None = None
              ) -> Iterator[tuple[ServedRig, Page, Page]]:
    """``prepare(served)`` runs before the pages connect (power, a scan, a pulled module)."""
    rig = build_rig(load_rig_spec(path), state_dir=None)
    served = serve_rig(rig, Access(None), port=free_port(), paused=True)  # an open rig
    try:
        if prepare is not None:
            prepare(served)
        first, second = Page(served.port), Page(served.port)
        try:
            wait(lambda: len(served.server.get_clients()) == 2)
            yield served, first, second
        finally:
            first.close()
            second.close()
    finally:
        served.stop()
