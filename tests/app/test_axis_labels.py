"""The servo axis scene's labels stay apart at the dashboard's default camera (app/ui/drive).

viser draws a "screen" label at a constant size on screen: 12 px per em at font_screen_scale
1 (client/src/label/LabelRenderer.tsx), a background 0.2 line heights wider and taller than
the text (labelLayout.ts), in the system font stack, Liberation Sans (Arial metrics) on this
machine. Whether two labels collide therefore depends on how many pixels one scene unit takes
at the camera the dashboard starts with; the tests read that camera off a real dashboard of
the rig and estimate each label's box from character widths rounded up from Arial's. The
estimate is conservative: a label drawn narrower than estimated only widens the gaps.

What a trainee must read (seed 004 ch. 2, CN2 inputs: pin 8 Negative limit switch = NL, pin 9
Positive limit switch = PL, pin 14 Home switch): the three switch labels, the caption with
position, velocity and the actuated switches, the drive's name and network LEDs (ch. 5).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import viser
from label_boxes import TOUCH_PX, VIEW_HEIGHT_PX, Box, label_box, overlaps

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.drive.axis_scene import (
    AXIS_BOTTOM,
    AXIS_TOP,
    FRONT,
    TRAVEL_MARGIN,
    AxisScene,
    legend_text,
    switch_label_anchors,
)

TWO_DRIVES = """
[rig]
name = "two drives on one Modbus line"
seed = 1
step_ms = 1

[[servo]]
id = "x"
node_id = 1

[[servo]]
id = "y"
node_id = 2
"""


@dataclass
class Axes:
    server: viser.ViserServer
    scenes: dict[str, AxisScene]
    px_per_unit: dict[str, float]  # at each axis' front plane, default camera


def axes_of(rig_text: str | None, tmp_path: Any) -> Iterator[Axes]:
    if rig_text is None:
        spec = load_rig_spec(DEFAULT_RIG)
    else:
        path = tmp_path / "rig.toml"
        path.write_text(rig_text)
        spec = load_rig_spec(path)
    runtime = Runtime(build_rig(spec, state_dir=None))
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        dashboard = Dashboard(server, runtime)
        assert dashboard.drives is not None
        cam = server.initial_camera
        eye, look = np.array(cam.position), np.array(cam.look_at)
        ahead = (look - eye) / np.linalg.norm(look - eye)
        scales = {}
        for drive_id, scene in dashboard.drives.scenes.items():
            depth = float(np.dot(np.array((6.0, FRONT, scene.z)) - eye, ahead))
            scales[drive_id] = VIEW_HEIGHT_PX / (2 * depth * math.tan(cam.fov / 2))
        yield Axes(server, dict(dashboard.drives.scenes), scales)
    finally:
        server.stop()


@pytest.fixture(scope="module", params=["default", "two_drives"])
def axes(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
         ) -> Iterator[Axes]:
    text = None if request.param == "default" else TWO_DRIVES
    yield from axes_of(text, tmp_path_factory.mktemp(request.param))


def drive_snap(axis: Mapping[str, float], carriage: float, **extra: Any) -> dict[str, Any]:
    snap: dict[str, Any] = {"powered": True, "display": "En", "fieldbus": "modbus",
                            "node_id": 1, "position_counts": round(carriage),
                            "velocity": 0.0, "limits": {}, "jammed": False,
                            "axis": {**axis, "carriage": carriage, "motor_turns": 0.0}}
    snap.update(extra)
    return snap


def states(axis: Mapping[str, float]) -> Iterator[dict[str, Any]]:
    """The carriage at each switch and at both end stops; the longest caption too."""
    low, high = min(axis.values()), max(axis.values())
    margin = (high - low) * TRAVEL_MARGIN
    for carriage in sorted({*axis.values(), low - margin, high + margin}):
        yield drive_snap(axis, carriage)
    yield drive_snap(axis, axis["pos_limit"], position_counts=-2147483648,
                     velocity=-100000.0, jammed=True,
                     limits={"neg": True, "home": True, "pos": True})


# The LEDs at their longest words, on an EtherCAT drive: the only one that draws them
# (tests/app/test_axis_bus_leds.py).
NETWORK = {"fieldbus": "ethercat",
           "leds": {"L/A IN": "flickering", "Status": "single_flash", "L/A OUT": "flickering",
                    "Error": "double_flash"}}


def all_boxes(scene: AxisScene, snap: Mapping[str, Any], px: float) -> list[Box]:
    scene.update("drive_co", {**snap, **NETWORK}, 0)
    return [label_box(label, px) for label in scene.labels()]


# The default rig's axis (static/rigs/default.toml) and the rig files' other shapes: the home
# switch beside a limit switch, on it (homing on a limit switch, DSP 402 methods 1 / 2), in
# the middle, beyond the positive limit.
AXES = [
    {"neg_limit": -60000.0, "pos_limit": 660000.0, "home_switch": -3000.0},
    {"neg_limit": -60000.0, "pos_limit": 660000.0, "home_switch": 650000.0},
    {"neg_limit": -60000.0, "pos_limit": 660000.0, "home_switch": -60000.0},
    {"neg_limit": -60000.0, "pos_limit": 660000.0, "home_switch": 660000.0},
    {"neg_limit": -18000.0, "pos_limit": 18000.0, "home_switch": 0.0},
    {"neg_limit": -18000.0, "pos_limit": 18000.0, "home_switch": 30000.0},
]


@pytest.mark.parametrize("axis", AXES, ids=["home_by_NL", "home_by_PL", "home_on_NL",
                                            "home_on_PL", "home_mid", "home_beyond_PL"])
def test_no_label_covers_another(axes: Axes, axis: dict[str, float]) -> None:
    """Each axis at the default camera: the switch labels, the caption, the carriage's
    position, the drive's name and LEDs, the motor: no two backgrounds overlap."""
    for drive_id, scene in axes.scenes.items():
        px = axes.px_per_unit[drive_id]
        fresh = AxisScene(axes.server, f"probe_{drive_id}", scene.z, scene.length)
        for snap in states(axis):
            boxes = all_boxes(fresh, snap, px)
            assert overlaps(boxes, TOUCH_PX / px) == [], (drive_id, legend_text(snap))


def test_the_drive_shows_an_l_a_led_per_port(axes: Axes) -> None:
    """Seed 004 ch. 5, the front: "L/A Status L/A Error" over "Ingresso RJ45 Uscita RJ45".
    The drive drew one L/A: the OUT port's link (a next slave cabled) was not shown."""
    scene = next(iter(axes.scenes.values()))
    fresh = AxisScene(axes.server, "probe_ports", scene.z, scene.length)
    snap = {**drive_snap(AXES[0], 0.0), "fieldbus": "ethercat",
            "leds": {"L/A IN": "flickering", "Status": "on", "L/A OUT": "off", "Error": "off"}}
    fresh.update("drive_ec", snap, 0)
    texts = [str(label.text) for label in fresh.labels()]
    assert [t for t in texts if t.startswith(("L/A", "Status", "Error"))] == [
        "L/A IN flickering", "Status on", "L/A OUT off", "Error off"]


def test_labels_stay_in_their_axis_band(axes: Axes) -> None:
    """Every label stays between the axis block's top and bottom (the next axis, and the
    line above, begin beyond them) and within the axis' length (the framed view)."""
    axis = AXES[0]
    for drive_id, scene in axes.scenes.items():
        px = axes.px_per_unit[drive_id]
        for snap in states(axis):
            for box in all_boxes(scene, snap, px):
                assert box.z1 <= scene.z + AXIS_TOP + 1e-6, box
                assert box.z0 >= scene.z + AXIS_BOTTOM - 1e-6, box
                if box.text.startswith("position"):
                    assert box.x1 <= scene.length, box


def test_switch_labels_name_the_seed_switches(axes: Axes) -> None:
    """NL, home and PL, each hanging from its own switch."""
    scene = next(iter(axes.scenes.values()))
    scene.update("drive", drive_snap(AXES[0], 0.0), 0)
    texts = sorted(str(label.text) for label in scene.labels())
    assert {"NL", "home", "PL"} <= set(texts)


@pytest.mark.parametrize(("xs", "anchors"), [
    # NL, home, PL left to right, home near NL: home opens to the right, away from NL.
    ({"neg": 3.7, "home": 4.3, "pos": 10.0},
     {"neg": "top-right", "home": "top-left", "pos": "top-left"}),
    # home near PL: it opens to the left, away from PL.
    ({"neg": 3.7, "home": 9.6, "pos": 10.0},
     {"neg": "top-right", "home": "top-right", "pos": "top-left"}),
    # home on NL (homing on the limit switch): NL left of the pair, home right of it.
    ({"neg": 3.7, "home": 3.7, "pos": 10.0},
     {"neg": "top-right", "home": "top-left", "pos": "top-left"}),
    # home on PL: home left of the pair, PL right of it.
    ({"neg": 3.7, "home": 10.0, "pos": 10.0},
     {"neg": "top-right", "home": "top-right", "pos": "top-left"}),
    # home beyond PL: PL is the middle one and opens toward NL.
    ({"neg": 3.7, "home": 10.0, "pos": 8.0},
     {"neg": "top-right", "pos": "top-right", "home": "top-left"}),
])
def test_switch_labels_open_away_from_their_neighbours(
        xs: dict[str, float], anchors: dict[str, str]) -> None:
    assert switch_label_anchors(xs) == anchors
