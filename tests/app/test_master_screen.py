"""The master's screen is readable where a scenario shows it: a focus on the master.

dc_sync_lost.toml's three pictures focus the master, whose screen carries its start-up phase
and the DC state (seed 003: COMPENSATING, NOT_SYNCHRONIZED ...), the story of the scenario.
The texts were screen labels sized to fit the screen at the whole line's camera (the widest
view): about 7 px an em in the focused picture, under the 12 px of the caption above it.
"""

from __future__ import annotations

from collections.abc import Iterator
from types import SimpleNamespace

import pytest
import viser
from label_boxes import EM_PX, VIEW_HEIGHT_PX, em_px, label_box, px_per_unit
from test_caption import VIEW_WIDTH_PX, project

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import CAPTION_SCALE, Dashboard
from app.ui.line.view import LineView

BOOT_STEPS = 5000  # the master in COMPENSATING (dc_sync_lost's first picture, at 4 s)


@pytest.fixture(scope="module")
def board() -> Iterator[Dashboard]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        dashboard = Dashboard(server, Runtime(rig))
        dashboard.tick()
        yield dashboard
    finally:
        server.stop()


def focused_camera(line: LineView, fov: float) -> SimpleNamespace:
    position, look_at = line.focus_camera("master", VIEW_WIDTH_PX / VIEW_HEIGHT_PX)
    return SimpleNamespace(position=position, look_at=look_at, up=(0.0, 0.0, 1.0), fov=fov)


@pytest.mark.parametrize("key", ["phase", "dc"])
def test_screen_text_is_caption_size_in_a_focus_on_the_master(board: Dashboard,
                                                              key: str) -> None:
    line = board.line
    assert line is not None
    label = line.scene.bodies["master"].paint.labels[key]
    assert str(label.text)  # "running", "DC COMPENSATING"
    camera = focused_camera(line, board.server.initial_camera.fov)
    px = px_per_unit(camera, label.position)
    assert em_px(label, px) >= EM_PX * CAPTION_SCALE, (key, em_px(label, px))


def test_screen_text_stays_in_the_focused_view(board: Dashboard) -> None:
    line = board.line
    assert line is not None
    camera = focused_camera(line, board.server.initial_camera.fov)
    for label in line.scene.bodies["master"].paint.labels.values():
        box = label_box(label, px_per_unit(camera, label.position))
        y = float(label.position[1])
        left, top = project(camera, (box.x0, y, box.z1))
        right, bottom = project(camera, (box.x1, y, box.z0))
        assert left >= 0 and right <= VIEW_WIDTH_PX, (label.text, left, right)
        assert top >= 0 and bottom <= VIEW_HEIGHT_PX, (label.text, top, bottom)
