"""The scenario caption above the line stays whole inside the 3D view at the default camera.

viser draws the caption as a screen label of constant size (tests/app/label_boxes.py); the 3D
view is the canvas between the docked panels of a 1280 x 720 window (app/ui/dashboard.py). A
caption as long as the longest of static/scenarios/ used to be one line wider than the view:
the side panels cut it at both ends, and its top touched the title bar.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import viser
from label_boxes import VIEW_HEIGHT_PX, label_box, px_per_unit

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import LEFT_WIDTH, RIGHT_WIDTH, Dashboard
from devices.events import Caption

SCENARIOS = Path(__file__).resolve().parents[2] / "static" / "scenarios"
VIEW_WIDTH_PX = 1280 - LEFT_WIDTH - RIGHT_WIDTH
EDGE_PX = 8.0  # the panels' borders and scroll bars take a few pixels of the view


def longest_caption() -> str:
    captions = [step["caption"] for path in SCENARIOS.glob("*.toml")
                for step in tomllib.loads(path.read_text(encoding="utf-8")).get("step", [])
                if "caption" in step]
    return max(captions, key=len)


def project(camera: object, point: tuple[float, float, float]) -> tuple[float, float]:
    """Pixel (x right, y down) of a scene point in the view, the look-at point at its centre."""
    eye, look = np.array(camera.position), np.array(camera.look_at)  # type: ignore[attr-defined]
    ahead = (look - eye) / np.linalg.norm(look - eye)
    right = np.cross(ahead, np.array(camera.up))  # type: ignore[attr-defined]
    right /= np.linalg.norm(right)
    up = np.cross(right, ahead)
    rel = np.array(point) - eye
    depth = float(np.dot(rel, ahead))
    scale = VIEW_HEIGHT_PX / (2 * depth * math.tan(camera.fov / 2))  # type: ignore[attr-defined]
    return (VIEW_WIDTH_PX / 2 + float(np.dot(rel, right)) * scale,
            VIEW_HEIGHT_PX / 2 - float(np.dot(rel, up)) * scale)


@pytest.fixture(scope="module")
def dashboard() -> Iterator[Dashboard]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    runtime = Runtime(rig)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        board = Dashboard(server, runtime)
        board.tick()
        yield board
    finally:
        server.stop()


def on_screen(camera: Any, label: Any) -> tuple[Any, tuple[float, float, float, float]]:
    """The caption's box in scene units and its (left, top, right, bottom) in view pixels."""
    box = label_box(label, px_per_unit(camera, label.position))
    y = float(label.position[1])
    left, top = project(camera, (box.x0, y, box.z1))
    right, bottom = project(camera, (box.x1, y, box.z0))
    return box, (left, top, right, bottom)


def test_the_longest_caption_fits_the_view(dashboard: Dashboard) -> None:
    text = longest_caption()
    assert len(text) > 200  # trscat_outputs_fallback.toml: what the audit saw cut
    # The runtime is not started: journal the caption as its simulation thread would.
    dashboard.runtime._journal_events([Caption(0, "scenario", text=text)])
    dashboard.tick()
    label = dashboard._caption
    shown = str(label.text)
    assert shown.split() == text.split()  # every word, broken at spaces only
    camera = dashboard.server.initial_camera
    box, (left, top, right, _) = on_screen(camera, label)
    assert left >= EDGE_PX and right <= VIEW_WIDTH_PX - EDGE_PX, (left, right, shown)
    assert top >= EDGE_PX, (top, shown)
    # ... and above the line, not over it.
    line = dashboard.line
    assert line is not None
    assert box.z0 >= line.bounds().z_max, (box.z0, line.bounds().z_max)


def test_the_caption_room_keeps_the_axes_in_view(dashboard: Dashboard) -> None:
    """The view looks higher to make room for the caption: the bottom of what it frames (the
    axes under the line and their switch labels) stays inside the view."""
    line = dashboard.line
    assert line is not None
    home = line.home
    _, bottom = project(dashboard.server.initial_camera, (home.x_min, 0.0, home.z_min))
    assert bottom <= VIEW_HEIGHT_PX - EDGE_PX, bottom


@pytest.mark.parametrize("device", ["master", "fastcat", "trscat", "cpx", "drive_ec-ecat"])
def test_a_focused_view_shows_the_caption_and_the_whole_device(dashboard: Dashboard,
                                                                device: str) -> None:
    """A scenario ``focus`` step moves the camera to one device: the caption (placed above
    the whole line before) was out of that view, and a demo viewer reads the caption there
    too. The caption moves above the focused device; both stay inside the view between the
    panels, the caption above the device, not over it."""
    line = dashboard.line
    assert line is not None
    dashboard.runtime._journal_events([Caption(0, "scenario", text=longest_caption())])
    dashboard.tick()
    line.focus(None, device)
    position, look_at = line.focus_camera(device, VIEW_WIDTH_PX / VIEW_HEIGHT_PX)
    camera = SimpleNamespace(position=position, look_at=look_at, up=(0.0, 0.0, 1.0),
                             fov=dashboard.server.initial_camera.fov)
    label = dashboard._caption
    box, (left, top, right, bottom) = on_screen(camera, label)
    assert left >= EDGE_PX and right <= VIEW_WIDTH_PX - EDGE_PX, (device, left, right)
    assert top >= EDGE_PX, (device, top)
    body = line.scene.focus_box(device)
    assert body is not None
    assert box.z0 >= body.z_max, (device, box.z0, body.z_max)  # above the device, not over it
    b_left, b_top = project(camera, (body.x_min, 0.0, body.z_max))
    b_right, b_bottom = project(camera, (body.x_max, 0.0, body.z_min))
    assert b_left >= EDGE_PX and b_right <= VIEW_WIDTH_PX - EDGE_PX, (device, b_left, b_right)
    assert bottom <= b_top and b_bottom <= VIEW_HEIGHT_PX - EDGE_PX, (device, b_top, b_bottom)
    line.show_all()  # "Show the whole line": the caption goes back above the whole line
    assert float(label.position[2]) >= line.bounds().z_max
    assert abs(float(label.position[0]) - line.home_caption[0]) < 1e-9
