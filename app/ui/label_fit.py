"""Where viser draws a 3D label in a view, estimated: which labels a camera's picture cuts.

viser 1.1 draws a "screen" label at a constant size on screen, 12 px an em at
font_screen_scale 1 (its client's label/LabelRenderer.tsx), a "scene" label at
font_scene_height scene units an em; a background 0.2 line heights wider and taller than the
text (labelLayout.ts), in the system font stack, Liberation Sans (Arial metrics) here. The
widths are Arial's rounded up, so a label drawn narrower than estimated only fits better.
tests/app/label_boxes.py measures the scene's labels with the same numbers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

EM_PX = 12.0  # viser: a screen label's em at font_screen_scale 1
LINE_EM = 1.117  # Arial / Liberation Sans ascent + descent (0.905 + 0.212 em)
PADDING = 0.2  # viser: background padding, a share of the line height
# Advance widths in em, rounded up from Arial's: narrow glyphs, wide ones, capitals, the rest.
NARROW = " .,:;·|'!ijlftrI/-()[]"
WIDE = "mwMW@%"


def char_em(ch: str) -> float:
    if ch in NARROW:
        return 0.34
    if ch in WIDE:
        return 0.95
    return 0.78 if ch.isupper() else 0.56


def text_em(text: str) -> tuple[float, int]:
    """(width of the widest line in em, number of lines)."""
    lines = text.split("\n")
    return max(sum(char_em(c) for c in line) for line in lines), len(lines)


@dataclass(frozen=True)
class View:
    """A camera's picture: pose, vertical field of view (radians) and size in pixels."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    fov: float
    width_px: float
    height_px: float
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        eye, look = np.array(self.position), np.array(self.look_at)
        ahead = (look - eye) / np.linalg.norm(look - eye)
        right = np.cross(ahead, np.array(self.up))
        right /= np.linalg.norm(right)
        object.__setattr__(self, "_axes", (eye, ahead, right, np.cross(right, ahead)))

    def project(self, point: Sequence[float]) -> tuple[float, float, float]:
        """(x right, y down) in pixels of a scene point, and pixels per scene unit there."""
        eye, ahead, right, up = self._axes  # type: ignore[attr-defined]
        rel = np.array([float(v) for v in point]) - eye
        depth = float(np.dot(rel, ahead))
        if depth <= 0:
            return math.nan, math.nan, 0.0
        scale = self.height_px / (2 * depth * math.tan(self.fov / 2))
        return (self.width_px / 2 + float(np.dot(rel, right)) * scale,
                self.height_px / 2 - float(np.dot(rel, up)) * scale, scale)


def label_rect(view: View, text: str, position: Sequence[float], anchor: str,
               em_px: float | None = None, em_units: float | None = None,
               ) -> tuple[float, float, float, float]:
    """(left, top, right, bottom) in pixels of a label's background in ``view``: a screen
    label gives ``em_px``, a scene label ``em_units``."""
    x, y, scale = view.project(position)
    if not scale:
        return (math.nan,) * 4  # type: ignore[return-value]
    em = em_px if em_px is not None else float(em_units or 0.0) * scale
    width_em, lines = text_em(text)
    line_h = LINE_EM * em
    pad = PADDING * line_h
    width, height = width_em * em + pad, lines * line_h + pad
    vertical, horizontal = anchor.split("-")
    left = {"left": x, "right": x - width}.get(horizontal, x - width / 2)
    top = {"top": y, "bottom": y - height}.get(vertical, y - height / 2)
    return left, top, left + width, top + height


def handle_rect(view: View, label: Any) -> tuple[float, float, float, float]:
    """:func:`label_rect` of a viser LabelHandle."""
    scene = label.font_size_mode == "scene"
    return label_rect(view, str(label.text), label.position, str(label.anchor),
                      None if scene else EM_PX * float(label.font_screen_scale),
                      float(label.font_scene_height) if scene else None)


def inside(rect: tuple[float, float, float, float], view: View, margin: float) -> bool:
    left, top, right, bottom = rect
    return (left >= margin and top >= margin and right <= view.width_px - margin
            and bottom <= view.height_px - margin)
