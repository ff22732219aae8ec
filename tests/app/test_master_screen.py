"""The master's screen is readable where a scenario shows it: a focus on the master.

dc_sync_lost.toml's three pictures focus the master, whose screen carries its start-up phase
and the DC state (seed 003: COMPENSATING, NOT_SYNCHRONIZED ...), the story of the scenario.
The texts are screen labels (one size on screen) sized to fit the screen at the whole line's
camera, the widest view: about 7 px an em in the focused picture, under the 12 px of the
caption above it. A scenario's focus, which every browser shares, now sizes them for its
zoom (app/ui/line/bodies.py MasterBody.zoom).
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from types import SimpleNamespace

import pytest
import viser
from label_boxes import EM_PX, VIEW_HEIGHT_PX, Box, em_px, label_box, px_per_unit
from served_dashboard import ticked_dashboard
from test_caption import VIEW_WIDTH_PX, project

from app.ui.dashboard import CAPTION_SCALE, Dashboard
from app.ui.glyphs import WARM_SCALES, bucket_px
from app.ui.line.bodies import SCREEN_SCALE
from app.ui.line.view import LineView

BOOT_STEPS = 5000  # the master in COMPENSATING (dc_sync_lost's first picture, at 4 s)


@pytest.fixture(scope="module")
def board() -> Iterator[Dashboard]:
    with ticked_dashboard(BOOT_STEPS) as dashboard:
        yield dashboard


def focused(board: Dashboard, device: str = "master") -> tuple[LineView, SimpleNamespace]:
    """A scenario's focus on ``device`` and the camera it gives the layout's 3D view."""
    line = board.line
    assert line is not None
    line.focus(None, device)
    board.tick()
    position, look_at = line.focus_camera(device, VIEW_WIDTH_PX / VIEW_HEIGHT_PX)
    fov = board.server.initial_camera.fov
    return line, SimpleNamespace(position=position, look_at=look_at, up=(0.0, 0.0, 1.0),
                                 fov=fov)


def screen_labels(line: LineView) -> dict[str, viser.LabelHandle]:
    labels = line.scene.bodies["master"].paint.labels
    return {key: labels[key] for key in ("phase", "dc")}


@pytest.mark.parametrize("key", ["phase", "dc"])
def test_screen_text_is_caption_size_in_a_focus_on_the_master(board: Dashboard,
                                                              key: str) -> None:
    line, camera = focused(board)
    label = screen_labels(line)[key]
    assert str(label.text)  # "running", "DC\ncompensating"
    px = px_per_unit(camera, label.position)
    assert em_px(label, px) >= EM_PX * CAPTION_SCALE, (key, em_px(label, px))


@pytest.mark.parametrize("device", ["master", "fastcat", "trscat", "cpx"])
def test_screen_text_stays_on_the_screen_in_a_focus(board: Dashboard, device: str) -> None:
    """Grown for the zoom, "DC" / "compensating" and the phase still fit the screen, in a
    focus on the master and in the less zoomed ones that show it too."""
    line, camera = focused(board, device)
    handle = board.server.scene._handle_from_node_name["/line/master/screen"]
    (x, _, z), (w, _, h) = handle.position, handle.dimensions
    screen = Box("screen", x - w / 2, x + w / 2, z - h / 2, z + h / 2)
    for label in screen_labels(line).values():
        box = label_box(label, px_per_unit(camera, label.position))
        tol = 1.0 / px_per_unit(camera, label.position)
        assert screen.x0 - tol <= box.x0 and box.x1 <= screen.x1 + tol, (device, box)
        assert screen.z0 - tol <= box.z0 and box.z1 <= screen.z1 + tol, (device, box)
        if device == "master":
            y = float(label.position[1])
            left, top = project(camera, (box.x0, y, box.z1))
            right, bottom = project(camera, (box.x1, y, box.z0))
            assert left >= 0 and right <= VIEW_WIDTH_PX and top >= 0 and bottom <= VIEW_HEIGHT_PX


def test_the_whole_line_gives_the_texts_their_size_back(board: Dashboard) -> None:
    line, _camera = focused(board)
    line.show_all()
    assert {float(lb.font_screen_scale) for lb in screen_labels(line).values()} == {
        SCREEN_SCALE}


def test_a_zoomed_text_is_drawn_from_a_warmed_glyph_atlas(board: Dashboard) -> None:
    """A scale in another atlas would pack its glyphs in whatever order the page meets them:
    two runs of a scenario would not give the same PNG bytes (app/ui/glyphs.py)."""
    line, _camera = focused(board)
    warm = {bucket_px(s) for s in WARM_SCALES}
    for label in screen_labels(line).values():
        assert bucket_px(float(label.font_screen_scale)) in warm, label.font_screen_scale


def test_the_phase_note_stays_on_the_screen_and_off_the_dc_state(board: Dashboard) -> None:
    """dc_sync_lost's pictures focus the master while DC holds the TRS-CAT and the CPX-E-EC in
    SAFEOP: "running" gets its note under it ("2 held"; the longest a four-slave line gives,
    "4 lost, 2 held" here) and, grown for the zoom, both lines stay on the screen and off the
    DC state's lines."""
    line, camera = focused(board)
    snap = copy.deepcopy(board.runtime.frame.snapshot)
    master = snap["devices"]["master"]
    master.update(phase="running", phase_note_short="4 lost, 2 held")
    master["dc"]["state"] = "NOT_SYNCHRONIZED"
    line.scene.update(snap, board.runtime.frame.t_us)
    labels = screen_labels(line)
    assert str(labels["phase"].text) == "running\n4 lost, 2 held"
    handle = board.server.scene._handle_from_node_name["/line/master/screen"]
    (x, _, z), (w, _, h) = handle.position, handle.dimensions
    screen = Box("screen", x - w / 2, x + w / 2, z - h / 2, z + h / 2)
    boxes = {key: label_box(label, px_per_unit(camera, label.position))
             for key, label in labels.items()}
    tol = 1.0 / px_per_unit(camera, labels["phase"].position)
    for box in boxes.values():
        assert screen.x0 - tol <= box.x0 and box.x1 <= screen.x1 + tol, box
        assert screen.z0 - tol <= box.z0 and box.z1 <= screen.z1 + tol, box
    assert boxes["phase"].z0 >= boxes["dc"].z1 - tol, boxes
    line.scene.update(board.runtime.frame.snapshot, board.runtime.frame.t_us)  # as it was
