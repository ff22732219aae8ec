"""An open rig served paused with two websocket pages on it, the stand-ins for two browsers of
the per-page tests (docs/dashboard.md "Several browsers"); the default rig, or one of one drive
and one dictionary, where no picker makes a page's forms its own."""

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


def powered(served: ServedRig) -> None:
    """A ``prepare``: the FastCAT powered and the line 3 s on (scanned, in OP), drawn."""
    served.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
    served.runtime.advance(3_000_000).result(timeout=30)
    served.dashboard.tick()


ONE_DRIVE = """
[rig]
name = "one drive on CANopen"
seed = 1
step_ms = 1

[[servo]]
id = "drive"
fieldbus = "canopen"
node_id = 2

[[fastcat]]
id = "fastcat"
modules = ["DI16", "DO16"]
"""


@contextmanager
def one_drive_pages(folder: Path) -> Iterator[tuple[ServedRig, Page, Page]]:
    """Two pages on ONE_DRIVE (written into ``folder``), after the CANopen node's boot-up and
    the first scan."""
    path = folder / "one_drive.toml"
    path.write_text(ONE_DRIVE)
    with two_pages(path, lambda s: s.runtime.advance(3_000_000).result(10)) as pages:
        yield pages
