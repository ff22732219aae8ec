"""The whole EtherCAT line in 3D, left to right with its cables.

Row 1: the master (a PC) and the FastCAT rail (``app.ui.rail_scene``, drawn by the
dashboard at x = 0). Row 2, under it: the other slaves in line order (TRS-CAT with its
expansions, CPX-E-EC with its modules, the drive's EtherCAT side). Cable ``i`` runs from the
master or slave ``i - 1`` to slave ``i``; a cable from the end of row 1 wraps under it to the
start of row 2. Line order, names and states come from the master snapshot (``slaves``:
``device``, or the station address matched against the devices' snapshots).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import viser

from app.ui.line.bodies import Body, MasterBody, RailFrame, SlaveBody, as_drawn
from app.ui.line.cables import LABEL_LIFT, THICK, Cable, OnCable, label_point, route
from app.ui.line.io_bodies import CpxBody, TrsCatBody
from app.ui.panels.per_client import instructor_for
from app.ui.rail_scene import BODY_H

logger = logging.getLogger(__name__)

MASTER_X0 = -3.8  # the master (2.6 wide) ends 1.2 before the rail: room for cable 0
ROW2_X0 = -3.0
ROW_GAP = 2.6  # between row 1's bottom and row 2's top: legend, cable, headers
ROW2_Z = -(BODY_H + ROW_GAP)
GAP_X = 0.7
CABLE_GAP_Z = -BODY_H / 2 - 1.35
LEGEND_DEPTH = 1.2  # room under row 2 for the LED words
CABLE_OUT = 0.5
TOP_EXTRA = 0.75  # state bar and header above a row
# A cable label's height at the closest zoom (a focus: ~60 px a unit; 0.58 of a 12 px em).
CABLE_LABEL_H = 0.2
# Called with (client, device id) when a body is clicked.
OnFocus = Callable[[viser.ClientHandle | None, str], None]


def line_order(master: Mapping[str, Any], devices: Mapping[str, Any]) -> list[str]:
    """Device ids of the line's slaves in position order."""
    by_address = {int(s["station_address"]): d for d, s in devices.items()
                  if isinstance(s, Mapping) and s.get("station_address") is not None
                  and s.get("kind") != "master"}
    order = []
    for slave in master.get("slaves") or []:
        device = slave.get("device") or by_address.get(int(slave.get("station_address", -1)))
        if device is not None:
            order.append(str(device))
    return order


def slave_entries(master: Mapping[str, Any], order: list[str]) -> dict[str, dict[str, Any]]:
    """Each line device's entry of the master snapshot (with its position)."""
    out = {}
    for i, (device, slave) in enumerate(zip(order, master.get("slaves") or [], strict=False)):
        out[device] = {"position": i, **slave}
    return out


def body_for(server: viser.ViserServer, device: str, snap: Mapping[str, Any], x0: float,
             z0: float) -> Body:
    kind = snap.get("kind")
    if kind == "trscat":
        return TrsCatBody(server, device, x0, z0, snap)
    if kind == "cpx_e_ec":
        return CpxBody(server, device, x0, z0, snap)
    return SlaveBody(server, device, x0, z0, snap)


@dataclass(frozen=True)
class Box:
    x_min: float
    x_max: float
    z_min: float
    z_max: float


class LineScene:
    def __init__(self, server: viser.ViserServer, snapshot: Mapping[str, Any], master_id: str,
                 rail_lengths: Mapping[str, float], on_focus: OnFocus,
                 on_cable: OnCable) -> None:
        devices = snapshot.get("devices") or {}
        master = devices.get(master_id) or {}
        self.master_id = master_id
        self.order = line_order(master, devices)
        self.master = MasterBody(server, MASTER_X0, 0.0)
        self.bodies: dict[str, Body] = {master_id: self.master}
        x_row2 = ROW2_X0
        for device in self.order:
            snap = as_drawn(devices, device)
            if device in rail_lengths:  # the FastCAT rail is row 1 (at x = 0)
                self.bodies[device] = RailFrame(server, device, 0.0, 0.0, rail_lengths[device])
                continue
            body = body_for(server, device, snap, x_row2, ROW2_Z)
            self.bodies[device] = body
            x_row2 += body.width + GAP_X
        for device, body in self.bodies.items():
            body.build()
            for node in body.clickables:
                node.on_click(lambda event, d=device: on_focus(event.client, d))
        # With a token the shared cables show no pulled one (a hidden cause); each instructor
        # connection draws them as they are over the shared ones (app/ui/line/cables.py).
        instructor = instructor_for(server)
        self.cables = [Cable(server, i, self._route(i), on_cable, instructor.shared)
                       for i in range(len(self.order))]
        self._own_cables = instructor.scene_part(
            lambda client: [Cable(client, i, self._route(i), on_cable)
                            for i in range(len(self.order))])

    def _route(self, index: int) -> list[tuple[float, float]]:
        upstream = self.bodies[self.order[index - 1]] if index else self.master
        downstream = self.bodies[self.order[index]]
        return route(upstream.port("out"), downstream.port("in"), CABLE_GAP_Z)

    def add_clickable(self, device: str, nodes: list[Any], on_focus: OnFocus) -> None:
        """Nodes drawn elsewhere (the FastCAT coupler) that focus ``device`` on a click."""
        for node in nodes:
            node.on_click(lambda event, d=device: on_focus(event.client, d))

    # ---- geometry -------------------------------------------------------------------------
    def bounds(self) -> Box:
        bodies = list(self.bodies.values())
        row2 = [b for b in bodies if b.z0 < 0]
        bottom = (ROW2_Z if row2 else 0.0) - BODY_H / 2 - LEGEND_DEPTH
        # Cables wrapping between the rows run 0.35 outside the bodies.
        return Box(min(b.x0 for b in bodies) - CABLE_OUT, max(b.x0 + b.width for b in bodies)
                   + CABLE_OUT, bottom, BODY_H / 2 + TOP_EXTRA)

    def focus_box(self, device: str) -> Box | None:
        body = self.bodies.get(device)
        if body is None:
            return None
        return Box(body.x0, body.x0 + body.width, body.z0 - BODY_H / 2 - 0.6,
                   body.z0 + BODY_H / 2 + TOP_EXTRA)

    def top_over(self, x_min: float, x_max: float, floor: float) -> float:
        """The highest point of the scene above ``floor`` between ``x_min`` and ``x_max``:
        the bodies with their state bars and headers, the cables and their labels (``floor``
        when nothing is there). A focused device's caption goes above it: under row 1 the
        line's cable 1 and its label run between the rows, just over row 2's headers."""
        top = floor

        def over(a: float, b: float) -> bool:
            return min(b, x_max) > max(a, x_min)

        for body in self.bodies.values():
            body_top = body.z0 + BODY_H / 2 + TOP_EXTRA
            if body_top > floor and over(body.x0, body.x0 + body.width):
                top = max(top, body_top)
        for cable in self.cables:
            for (xa, za), (xb, zb) in zip(cable.points, cable.points[1:], strict=False):
                if max(za, zb) > floor and over(min(xa, xb), max(xa, xb)):
                    top = max(top, max(za, zb) + THICK / 2)
            label = label_point(cable.points)
            if label[1] > floor and over(label[0] - 0.5, label[0] + 0.5):
                top = max(top, label[1] + LABEL_LIFT + CABLE_LABEL_H)
        return top

    # ---- per frame ------------------------------------------------------------------------
    def update(self, snapshot: Mapping[str, Any], t_us: int) -> None:
        devices = snapshot.get("devices") or {}
        master = devices.get(self.master_id) or {}
        entries = slave_entries(master, self.order)
        self.master.update_master_frame(master, self.master.update(master, t_us))
        for position, device in enumerate(self.order):
            body = self.bodies[device]
            words = body.update(as_drawn(devices, device), t_us)
            body.update_frame(entries.get(device, {}), position, words, master.get("target"))
        cables = {int(c.get("index", i)): c for i, c in enumerate(master.get("cables") or [])}
        for cable in self.cables:
            cable.show(cables.get(cable.index, {}))
        for own in self._own_cables.each():
            try:
                for cable in own:
                    cable.show(cables.get(cable.index, {}))
            except Exception:  # a page that just left: forgotten by its disconnect
                logger.debug("instructor's cables not drawn", exc_info=True)

    # ---- tests ----------------------------------------------------------------------------
    def led_colours(self, device: str) -> dict[str, tuple[int, int, int]]:
        body = self.bodies.get(device)
        return body.paint.colours() if body is not None else {}

    def text(self, device: str, key: str) -> str:
        body = self.bodies.get(device)
        return body.paint.text(key) if body is not None else ""
