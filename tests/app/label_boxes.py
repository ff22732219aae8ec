"""Where viser draws a scene label, estimated: the tests of the axis and line scenes' labels.

viser draws a "screen" label at a constant size on screen: 12 px per em at font_screen_scale
1 (client/src/label/LabelRenderer.tsx), a background 0.2 line heights wider and taller than
the text (labelLayout.ts), in the system font stack, Liberation Sans (Arial metrics) on this
machine. Whether two labels collide therefore depends on how many pixels one scene unit takes
at the camera the dashboard starts with; the tests read that camera off a real dashboard and
estimate each label's box from character widths rounded up from Arial's. The estimate is
conservative: a label drawn narrower than estimated only widens the gaps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import viser

from app.ui.label_fit import EM_PX, LINE_EM, PADDING, char_em

VIEW_HEIGHT_PX = 670  # the 3D view between the docked panels of 1280 x 720 (app/ui/dashboard.py)
TOUCH_PX = 1.0  # backgrounds may touch; more than this is an overlap
# The metrics (EM_PX, LINE_EM, PADDING, char_em) are app/ui/label_fit.py's, which a focused
# view uses to hide the labels its border would cut: one estimate for both.
__all__ = ["EM_PX", "LINE_EM", "PADDING", "TOUCH_PX", "VIEW_HEIGHT_PX", "Box", "char_em",
           "em_px", "label_box", "overlaps", "px_per_unit"]


@dataclass(frozen=True)
class Box:
    """A label's background (or a solid part) on a front plane, in scene units (x right, z up)."""

    text: str
    x0: float
    x1: float
    z0: float
    z1: float

    def overlap(self, other: Box, tol: float) -> bool:
        return (min(self.x1, other.x1) - max(self.x0, other.x0) > tol
                and min(self.z1, other.z1) - max(self.z0, other.z0) > tol)


def em_px(label: viser.LabelHandle, px_per_unit: float) -> float:
    """A label's em in screen pixels: fixed for a "screen" label, its scene height times the
    zoom for a "scene" label (font_scene_height is its em in scene units: viser's
    label/LabelRenderer.tsx baseFontSize)."""
    if label.font_size_mode == "scene":
        return float(label.font_scene_height) * px_per_unit
    return EM_PX * float(label.font_screen_scale)


def label_box(label: viser.LabelHandle, px_per_unit: float) -> Box:
    """viser's layoutLabel, from the label's text, anchor and scale."""
    em = em_px(label, px_per_unit) / px_per_unit
    lines = str(label.text).split("\n")
    line_h = LINE_EM * em
    pad = PADDING * line_h
    width = max(sum(char_em(c) for c in line) for line in lines) * em + pad
    height = len(lines) * line_h + pad
    vertical, horizontal = str(label.anchor).split("-")
    x, _, z = (float(v) for v in label.position)
    x0 = {"left": x, "right": x - width}.get(horizontal, x - width / 2)
    z1 = {"top": z, "bottom": z + height}.get(vertical, z + height / 2)
    return Box(str(label.text), x0, x0 + width, z1 - height, z1)


def overlaps(boxes: list[Box], tol: float) -> list[tuple[str, str]]:
    return [(a.text, b.text) for i, a in enumerate(boxes) for b in boxes[i + 1:]
            if a.overlap(b, tol)]


def px_per_unit(camera: Any, point: Sequence[float]) -> float:
    """Screen pixels per scene unit at ``point`` for ``camera`` (position, look_at, fov):
    the view's height over the frustum's height at the point's depth."""
    eye, look = np.array(camera.position), np.array(camera.look_at)
    ahead = (look - eye) / np.linalg.norm(look - eye)
    depth = float(np.dot(np.array(point) - eye, ahead))
    return VIEW_HEIGHT_PX / (2 * depth * math.tan(camera.fov / 2))
