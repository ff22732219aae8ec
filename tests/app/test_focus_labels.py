"""A scenario's focused view shows no label cut by its border (app/ui/line/focus_labels.py).

A screen label keeps its size whatever the zoom, so in a view zoomed on one device the
neighbours' labels ran past the picture's edge (cpx_short_circuit's pictures: "ble 0",
"INK-ACT OUT flickering", half of row 2's first header, the axis caption cut at the bottom).
Checked in the 3D view of the 1280 x 720 layout the screenshots are taken at, with the label
estimate of tests/app/label_boxes.py (app/ui/label_fit.py).
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest
import viser
from served_dashboard import ticked_dashboard

from app.ui.dashboard import VIEW_ASPECT, VIEW_HEIGHT_PX, Dashboard
from app.ui.label_fit import View, handle_rect, inside
from app.ui.line.view import CAMERA_FOV_DEG, LineView

BOOT_STEPS = 6000  # the line in OP: every label at its working text
DEVICES = ["master", "fastcat", "trscat", "cpx", "drive_ec-ecat"]


@pytest.fixture(scope="module")
def board() -> Iterator[Dashboard]:
    with ticked_dashboard(BOOT_STEPS) as dashboard:
        yield dashboard


def line_of(board: Dashboard) -> LineView:
    assert board.line is not None
    return board.line


def shown_labels(board: Dashboard) -> dict[str, viser.LabelHandle]:
    # viser lists no scene nodes publicly; the server's registry is what browsers are sent.
    return {n: h for n, h in board.server.scene._handle_from_node_name.items()
            if isinstance(h, viser.LabelHandle) and h.visible and str(h.text)
            and n != "/caption"}


def focused_view(line: LineView, device: str) -> View:
    position, look_at = line.focus_camera(device, VIEW_ASPECT)
    return View(position, look_at, math.radians(CAMERA_FOV_DEG),
                VIEW_ASPECT * VIEW_HEIGHT_PX, VIEW_HEIGHT_PX)


@pytest.mark.parametrize("device", DEVICES)
def test_no_label_is_cut_by_a_scenario_focus(board: Dashboard, device: str) -> None:
    line = line_of(board)
    line.focus(None, device)  # a scenario's focus step
    board.tick()
    view = focused_view(line, device)
    cut = [(name, str(h.text)) for name, h in shown_labels(board).items()
           if not inside(handle_rect(view, h), view, 0.0)]
    assert cut == []


@pytest.mark.parametrize("device", DEVICES)
def test_the_focused_device_keeps_its_labels(board: Dashboard, device: str) -> None:
    """Only what the border cuts goes: the focused device reads whole, and so does a
    neighbour that fits (the FastCAT beside the master)."""
    line = line_of(board)
    line.focus(None, device)
    board.tick()
    root = "/fastcat/" if device == "fastcat" else f"/line/{device}/"
    assert not [n for n in line.labels.hidden() if n.startswith(root)]
    if device == "master":
        assert "/fastcat/coupler/led_RUN_label" in shown_labels(board)


def test_the_whole_line_brings_every_label_back(board: Dashboard) -> None:
    """Every label shown before the focus is shown again (a drive's alarm label, hidden while
    the drive has no alarm, stays hidden: it has nothing to say)."""
    line = line_of(board)

    def shown() -> set[str]:
        return {n for n, h in board.server.scene._handle_from_node_name.items()
                if isinstance(h, viser.LabelHandle) and h.visible
                and not n.startswith(("/glyphs/", "/caption"))}

    line.show_all()  # the board is shared: an earlier test may have left a focus
    board.tick()
    before = shown()
    line.focus(None, "cpx")
    board.tick()
    assert line.labels.hidden()
    line.show_all()
    board.tick()
    assert line.labels.hidden() == []
    assert shown() == before
