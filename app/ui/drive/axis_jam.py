"""An instructor connection's jammed load over the shared axis (docs/classroom.md).

With a token the shared axis (``AxisScene(causes=False)``) shows no jam: a jammed load is an
injected cause, and a trainee reads its symptoms only. Each instructor connection draws the
red carriage and the caption with "load jammed" in its own scene (``client.scene``), under the
shared nodes' names: in viser 1.1.1 a client's node shadows the server's of the same name on
that page only, and removing it shows the shared one again. Only while the load is jammed;
then the carriage does not move, so the copy is rarely redrawn.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import viser

from app.ui.drive.axis_scene import (
    CARRIAGE_JAMMED,
    CARRIAGE_SIZE,
    LEGEND_ANCHOR,
    LEGEND_SCALE,
    AxisScene,
    legend_label,
)


class AxisJam:
    def __init__(self, client: viser.ClientHandle, axis: AxisScene) -> None:
        self._scene = client.scene
        self._axis = axis
        self._nodes: tuple[Any, Any] | None = None
        self._sent: tuple[Any, ...] = ()

    def show(self, snap: Mapping[str, Any]) -> None:
        """After the shared axis took ``snap`` (its drive's snapshot)."""
        if not snap.get("jammed"):
            if self._nodes is not None:
                for node in self._nodes:
                    node.remove()
                self._nodes, self._sent = None, ()
            return
        at, text, legend_at = self._axis.carriage_at(), legend_label(snap), self._axis.legend_at()
        if (at, text, legend_at) == self._sent:
            return
        root = self._axis.root
        if self._nodes is None:
            self._nodes = (
                self._scene.add_box(f"{root}/carriage", color=CARRIAGE_JAMMED,
                                    dimensions=CARRIAGE_SIZE, position=at),
                self._scene.add_label(f"{root}/legend", text, position=legend_at,
                                      anchor=LEGEND_ANCHOR, font_screen_scale=LEGEND_SCALE))
        else:
            carriage, legend = self._nodes
            carriage.position, legend.text, legend.position = at, text, legend_at
        self._sent = (at, text, legend_at)
