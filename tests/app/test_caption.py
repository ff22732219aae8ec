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
from label_boxes import TOUCH_PX, VIEW_HEIGHT_PX, label_box, px_per_unit
from served_dashboard import ticked_dashboard

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
    with ticked_dashboard() as dashboard:
        yield dashboard


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


# ---- what the caption may not cover in a focused view -----------------------------------------
Rect = tuple[float, float, float, float]  # left, top, right, bottom in view pixels


def rect_on_screen(camera: Any, x0: float, x1: float, z0: float, z1: float, y: float) -> Rect:
    corners = [project(camera, (x, y, z)) for x in (x0, x1) for z in (z0, z1)]
    return (min(c[0] for c in corners), min(c[1] for c in corners),
            max(c[0] for c in corners), max(c[1] for c in corners))


def solid_on_screen(camera: Any, handle: viser.BoxHandle) -> Rect:
    """A box of the scene (a body, an LED, a cable stretch turned about y) by its front face."""
    (x, y, z), (w, d, h) = handle.position, handle.dimensions
    qw, _, qy, _ = (float(v) for v in handle.wxyz)
    angle = 2 * math.atan2(qy, qw)  # cables turn about +y only (app/ui/line/cables.py)
    half_x = abs(math.cos(angle)) * w / 2 + abs(math.sin(angle)) * h / 2
    half_z = abs(math.sin(angle)) * w / 2 + abs(math.cos(angle)) * h / 2
    return rect_on_screen(camera, x - half_x, x + half_x, z - half_z, z + half_z, y - d / 2)


def label_on_screen(camera: Any, handle: viser.LabelHandle) -> Rect:
    box = label_box(handle, px_per_unit(camera, handle.position))
    return rect_on_screen(camera, box.x0, box.x1, box.z0, box.z1, float(handle.position[1]))


def covered(a: Rect, b: Rect) -> bool:
    return (min(a[2], b[2]) - max(a[0], b[0]) > TOUCH_PX
            and min(a[3], b[3]) - max(a[1], b[1]) > TOUCH_PX)


@pytest.mark.parametrize("device", ["master", "fastcat", "trscat", "cpx", "drive_ec-ecat"])
def test_a_focused_caption_covers_no_cable_label_or_body(dashboard: Dashboard,
                                                         device: str) -> None:
    """The sales walkthrough's close-ups of the CPX-E-EC had the caption over cable 1 and its
    label (the cable runs between the rows, above row 2's headers): the caption goes above
    the highest part of the scene over the focused device, so in the focused view it covers
    nothing of the line, the rail or their labels."""
    line = dashboard.line
    assert line is not None
    dashboard.runtime._journal_events([Caption(0, "scenario", text=longest_caption())])
    dashboard.tick()
    line.focus(None, device)
    position, look_at = line.focus_camera(device, VIEW_WIDTH_PX / VIEW_HEIGHT_PX)
    camera = SimpleNamespace(position=position, look_at=look_at, up=(0.0, 0.0, 1.0),
                             fov=dashboard.server.initial_camera.fov)
    caption = label_on_screen(camera, dashboard._caption)
    hits = []
    nodes = dict(dashboard.server.scene._handle_from_node_name)  # what browsers are sent
    for name, handle in nodes.items():
        if name == "/caption" or not getattr(handle, "visible", True):
            continue
        if isinstance(handle, viser.LabelHandle) and str(handle.text).strip():
            rect = label_on_screen(camera, handle)
        elif isinstance(handle, viser.BoxHandle):
            rect = solid_on_screen(camera, handle)
        else:
            continue
        if rect[3] > 0 and rect[1] < VIEW_HEIGHT_PX and covered(caption, rect):
            hits.append((name, str(getattr(handle, "text", ""))))
    assert any("/cable" in name for name in nodes)  # the cables are among what is checked
    assert hits == [], (device, hits)
    line.show_all()
