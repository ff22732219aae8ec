"""The cables of the line: one polyline of thin boxes per cable, clickable to pull / re-plug.

Cable ``i`` feeds line position ``i`` (master snapshot ``cables``). Plugged (the snapshot's
``plugged``: the master's cable and both ends, docs/ethercat-master.md): a dark green cable
from the upstream port (right side, low) to the downstream port (left side, low), wrapping
under the row when the next device starts a new row. Pulled: red, and its end hangs loose in
front of the port it came out of (the downstream IN port's, or the upstream OUT port's when
only a slave's own OUT plug is out, ``pulled_at``), with "pulled" next to it.

The label sits over the middle of the cable's longest stretch. Between two bodies of a row
that stretch is narrower than "cable 2 pulled" at the default camera (labels keep their size
on screen), so there "pulled" goes on a second line; the long stretch between the rows keeps
one line, under the rail's legend. The end that is out is not written there (it does not fit
between two bodies); the Line tab's status says it (:func:`pulled_text`).

A click moves the master's own cable (``master_pulled``), as the Line controls' Pull / Plug
do: it pulls a cable the master has in, also one drawn pulled because a slave's plug is out.

With an instructor token a pulled cable is a hidden cause (only the instructor pulls one, the
master's or a slave's own plug): the shared drawing (``causes=False``) shows every cable in
its ports, as a trainee sees the real rig (the LINK / ACT LEDs at both ends go dark), and each
instructor connection draws the cables as they are under the same node names, which shadow
the shared ones on that page only (``client.scene``, viser 1.1.1; app/ui/line/scene.py).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import viser

from app.ui.line.painter import FRONT_Y

Point = tuple[float, float]  # (x, z) on the front plane

PLUGGED = (25, 120, 80)
PULLED = (220, 30, 30)
THICK = 0.14
CABLE_Y = FRONT_Y - 0.15
ONE_LINE_STRETCH = 2.5  # a stretch at least this long takes "cable i pulled" on one line
LABEL_LIFT = 0.12  # the label's bottom over the cable
# Called with (client, cable index, the master's cable plugged now) on a click.
OnCable = Callable[[viser.ClientHandle | None, int, bool], None]


def route(start: Point, end: Point, gap_z: float) -> list[Point]:
    """From an out port to an in port: straight on one row, else down to ``gap_z``, across,
    and up or down into the port."""
    (x0, z0), (x1, z1) = start, end
    if abs(z0 - z1) < 1e-6 and x0 < x1:
        return [start, end]
    return [start, (x0 + 0.35, z0), (x0 + 0.35, gap_z), (x1 - 0.35, gap_z), (x1 - 0.35, z1),
            end]


def pulled_route(points: Sequence[Point], at_start: bool = False) -> list[Point]:
    """The cable with its plug out: the last stretch stops short and the end hangs down;
    ``at_start``: the first stretch, out of the upstream (OUT) port."""
    if at_start:
        return pulled_route(points[::-1])[::-1]
    *head, (xa, za), (xb, zb) = points
    cut = (xa + 0.45 * (xb - xa), za + 0.45 * (zb - za))
    ahead = -0.2 if xb < xa else 0.2  # the loose end falls on, away from where it came from
    return [*head, (xa, za), cut, (cut[0] + ahead, cut[1] - 0.7)]


def pulled_text(cable: Mapping[str, Any]) -> str:
    """"" for a plugged cable, else what the snapshot says is out: "pulled" (the master's
    ``pull_cable``), "pulled at trscat OUT" (a slave's own plug), "pulled, also at cpx IN"
    (both)."""
    if cable.get("plugged", True):
        return ""
    ends = [str(end) for end in cable.get("pulled_at") or []]
    if not ends:
        return "pulled"
    at = "at " + " and ".join(ends)
    return f"pulled, also {at}" if cable.get("master_pulled") else f"pulled {at}"


def hangs_at_start(cable: Mapping[str, Any]) -> bool:
    """Only the upstream device's own OUT plug is out: that end hangs."""
    ends = list(cable.get("pulled_at") or [])
    return not cable.get("master_pulled") and bool(ends) and all(
        str(end).endswith(" OUT") for end in ends)


def longest_stretch(points: Sequence[Point]) -> tuple[Point, Point]:
    return max(itertools.pairwise(points), key=lambda ab: math.dist(ab[0], ab[1]))


def label_point(points: Sequence[Point]) -> Point:
    """Middle of the longest stretch, where the cable's name goes."""
    a, b = longest_stretch(points)
    return ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)


def cable_label(index: int, plugged: bool, points: Sequence[Point]) -> str:
    """"cable 2", or "cable 2 pulled" (on two lines where the stretch is short). Which end is
    out is drawn (the end that hangs), not written: "pulled at trscat OUT" does not fit
    between two bodies at the default camera (tests/app/test_line_labels.py); the Line tab's
    status says it."""
    if plugged:
        return f"cable {index}"
    sep = " " if math.dist(*longest_stretch(points)) >= ONE_LINE_STRETCH else "\n"
    return f"cable {index}{sep}pulled"


class Cable:
    def __init__(self, owner: viser.ViserServer | viser.ClientHandle, index: int,
                 points: list[Point], on_click: OnCable, causes: bool = True) -> None:
        """``owner``: the server (every page) or one connection (its page only);
        ``causes=False`` draws every cable plugged (a trainee's view, module docstring)."""
        self._scene = owner.scene
        self.causes = causes
        self.index = index
        self.points = points
        self._on_click = on_click
        self._nodes: list[Any] = []
        self.plugged: bool | None = None  # as drawn: the cable and both its ends
        self.master_plugged = True  # what a click moves
        self.label_text = ""
        self._drawn: tuple[bool, bool] | None = None

    def show(self, cable: Mapping[str, Any]) -> None:
        """Draw the snapshot's ``cable``; redraw when what it shows changes (a handful of
        boxes)."""
        plugged = bool(cable.get("plugged", True))
        # An older snapshot without the key: its "plugged" was the master's cable.
        self.master_plugged = not cable.get("master_pulled", not plugged)
        at_start = hangs_at_start(cable)
        if not self.causes:
            # A click does what the drawing offers (pull): a refused "plug_cable" would tell
            # the trainee the cable is out.
            plugged, at_start, self.master_plugged = True, False, True
        if (plugged, at_start) == self._drawn:
            return
        # Recorded once the drawing is whole: a write that fails half-way (the dashboard logs
        # it) leaves it unrecorded, so the next frame draws the cable again, not never.
        self._drawn, self.plugged = None, plugged
        while self._nodes:  # each node forgotten as it goes: a retry removes only the rest
            self._nodes.pop().remove()
        points = self.points if plugged else pulled_route(self.points, at_start)
        colour = PLUGGED if plugged else PULLED
        root = f"/line/cable{self.index}"
        # Numbered as drawn: a pulled cable has one stretch more than the same cable plugged,
        # so an instructor's copy shadows every node of the shared (plugged) drawing.
        stretches = [(a, b) for a, b in itertools.pairwise(points) if math.dist(a, b) >= 1e-6]
        for n, (a, b) in enumerate(stretches):
            length = math.dist(a, b)
            angle = math.atan2(-(b[1] - a[1]), b[0] - a[0])  # about +y: x turns toward -z
            box = self._scene.add_box(
                f"{root}/seg{n}", color=colour, dimensions=(length + THICK, THICK, THICK),
                position=((a[0] + b[0]) / 2, CABLE_Y, (a[1] + b[1]) / 2),
                wxyz=(math.cos(angle / 2), 0.0, math.sin(angle / 2), 0.0))
            self._nodes.append(box)
            box.on_click(self._clicked)
        x, z = label_point(self.points)
        text = cable_label(self.index, plugged, self.points)
        self._nodes.append(self._scene.add_label(
            f"{root}/label", text, position=(x, CABLE_Y, z + LABEL_LIFT),
            anchor="bottom-center", font_screen_scale=0.58))
        self.label_text, self._drawn = text, (plugged, at_start)

    def _clicked(self, event: Any) -> None:
        self._on_click(event.client, self.index, self.master_plugged)
