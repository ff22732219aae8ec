"""An instructor connection's modules without supply over the shared rail (docs/classroom.md).

With a token the shared rail (``RailScene(causes=False)``) draws every module powered: a
module's supply is a hidden cause (only the instructor switches it off, the Rail and power
folder's *Module powered*), and a trainee reads what the real module shows, its LEDs dark.
Before, the shared rail greyed the module and wrote "power off" under it on every page, next
to the Causes row ("its supply is off") that only the instructor's page gets. Each instructor
connection draws the greyed body and the note in its own scene (``client.scene``) under the
shared nodes' names, which shadow them on that page only (viser 1.1.1), as the pulled cables
(app/ui/line/cables.py) and the jammed load (app/ui/drive/axis_jam.py) do.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import Any

import viser

from app.ui.panels.per_client import Instructor
from app.ui.rail_scene import RailScene, slot_note

logger = logging.getLogger(__name__)


class RailPower:
    """One connection's drawing of one rail's modules without supply."""

    def __init__(self, client: viser.ClientHandle, rail: RailScene) -> None:
        self._scene = client.scene
        self._rail = rail
        self._nodes: dict[int, list[Any]] = {}
        self._drawn: dict[int, tuple[Any, ...]] = {}

    def show(self, snap: Mapping[str, Any]) -> None:
        """After the shared rail took ``snap`` (its FastCAT's snapshot)."""
        off = {int(e["slot"]): e for e in snap.get("rail") or []
               if e.get("type") is not None and e.get("plugged", True)
               and not e.get("powered", True)}
        for slot in [s for s in self._nodes if s not in off]:
            self._remove(slot)
        for slot, entry in off.items():
            # A rebuilt shared slot was sent after this page's nodes: drawn again over it.
            key = (self._rail.builds.get(slot), entry.get("type"), slot_note(entry))
            if self._drawn.get(slot) == key:
                continue
            self._remove(slot)
            self._nodes[slot] = [self._rail.add_body(self._scene, entry),
                                 self._rail.add_note(self._scene, slot, slot_note(entry))]
            self._drawn[slot] = key

    def _remove(self, slot: int) -> None:
        for node in self._nodes.pop(slot, []):
            node.remove()
        self._drawn.pop(slot, None)


class RailPowers:
    """Every instructor connection's :class:`RailPower` for each rail; none on an open rig,
    whose shared rail shows the modules as they are."""

    def __init__(self, instructor: Instructor, rails: Sequence[RailScene]) -> None:
        self._part = instructor.scene_part(
            lambda client: [RailPower(client, rail) for rail in rails])

    def update(self, snaps: Sequence[Mapping[str, Any]]) -> None:
        for own in self._part.each():
            try:
                for power, snap in zip(own, snaps, strict=False):
                    power.show(snap)
            except Exception:  # a page that just left: forgotten by its disconnect
                logger.debug("instructor's modules without supply not drawn", exc_info=True)
