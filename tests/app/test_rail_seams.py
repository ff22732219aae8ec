"""The seams between the FastCAT rail's housings read the same everywhere (app/ui/rail_scene.py).

A housing is narrower than its slot (MODULE_W * 0.92), so a seam is a gap between two boxes.
Seen at an angle, a seam shows the neighbour's side face; where the camera looks straight
along it (too_many_analog's picture: between modules 4 and 5, the middle of its ten-module
rail) it showed what lies behind: the background above and below the DIN rail, a broken
white-and-grey line unlike every other seam. A back plate behind each housing closes every
seam with the colour of a side face. Checked on the scene's data: the boxes and where they are.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
import viser
from served_dashboard import local_server

from app.ui.rail_scene import BODY_H, FRONT_Y, RailScene

MODULES = ["DI16", "AI8D", "AI8C", "AI4D", "AO4", "AI8TC", "AB4P4", "AI4C", "AI4P", "AO4H"]


@pytest.fixture()
def server() -> Iterator[viser.ViserServer]:
    with local_server() as server:
        yield server


def rail(types: list[str | None], unplugged: tuple[int, ...] = ()) -> dict[str, Any]:
    return {"rail": [{"slot": i, "type": t, "plugged": i not in unplugged}
                     for i, t in enumerate(types, start=1)], "leds": {}}


def solid_boxes(server: viser.ViserServer) -> list[tuple[str, float, float, float, float]]:
    """(name, x0, x1, z0, z1) of every opaque box between the fronts and the rail."""
    out = []
    # viser lists no scene nodes publicly; the server's registry is what browsers are sent.
    for name, handle in server.scene._handle_from_node_name.items():
        if not isinstance(handle, viser.BoxHandle) or handle.opacity not in (None, 1.0):
            continue
        (x, y, z), (w, d, h) = handle.position, handle.dimensions
        if y - d / 2 > FRONT_Y and y + d / 2 < 1.5:
            out.append((name, x - w / 2, x + w / 2, z - h / 2, z + h / 2))
    return out


def housing(server: viser.ViserServer, name: str) -> tuple[float, float]:
    handle = server.scene._handle_from_node_name[name]
    assert isinstance(handle, viser.BoxHandle)
    x, w = handle.position[0], handle.dimensions[0]
    return x - w / 2, x + w / 2


def closed(boxes: list[tuple[str, float, float, float, float]], x0: float, x1: float) -> bool:
    """Whether the seam x0..x1 is covered over the housings' whole height by opaque boxes."""
    spans = sorted((a, b) for _, a, b, lo, hi in boxes
                   if lo <= -BODY_H / 2 + 1e-6 and hi >= BODY_H / 2 - 1e-6 and b > x0 and a < x1)
    reach = x0
    for a, b in spans:
        if a > reach + 1e-6:
            return False
        reach = max(reach, b)
    return reach >= x1 - 1e-6


def seams(server: viser.ViserServer, slots: list[int]) -> list[tuple[str, float, float]]:
    names = ["/fastcat/coupler/body"] + [f"/fastcat/slot{s:02d}/body" for s in slots]
    edges = [housing(server, n) for n in names]
    return [(f"{a} | {b}", left[1], right[0])
            for (a, left), (b, right) in zip(zip(names, edges, strict=True),
                                             zip(names[1:], edges[1:], strict=True),
                                             strict=False)]


def test_every_seam_of_a_full_rail_is_closed(server: viser.ViserServer) -> None:
    scene = RailScene(server, "fastcat")
    scene.build_coupler()
    scene.update(rail(list(MODULES)), 0)
    boxes = solid_boxes(server)
    open_seams = [name for name, x0, x1 in seams(server, list(range(1, 11)))
                  if not closed(boxes, x0, x1)]
    assert open_seams == []


def test_an_empty_or_unplugged_slot_stays_see_through(server: viser.ViserServer) -> None:
    """The plate belongs to a plugged module: an empty slot and a pulled module's slot show
    the rail behind them, as before."""
    scene = RailScene(server, "fastcat")
    scene.build_coupler()
    scene.update(rail(["DI16", None, "DO16", "AI8D"], unplugged=(3,)), 0)
    boxes = solid_boxes(server)
    for slot in (2, 3):
        x = 2.6 + slot - 0.5
        assert not closed(boxes, x - 0.3, x + 0.3), slot
    assert closed(boxes, *seams(server, [1])[0][1:])
