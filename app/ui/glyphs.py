"""The 3D labels' glyphs packed in one order, so that two runs draw the same text pixels.

viser 1.1 draws every 3D label from a glyph atlas, one per font-pixel bucket (its client's
label/GlyphAtlas.ts): a glyph is rasterised and packed after the others the first time a label
shows it. Which glyph came first depended on wall time: the texts a page happened to draw
while a paused rig was stepped to the next checkpoint (a position counting up, "t = 4.7 s")
and viser's 5 ms per-frame rasterising budget. A glyph packed elsewhere in the atlas is
sampled at texture coordinates that round differently, so the same label came out with a few
anti-aliased pixels one or two grey levels apart: `scenario run --screenshots` twice gave
different PNG bytes (0 to 20 such pixels a picture, always on label text).

The fix: the first labels of the scene (invisible: viser registers a label's text whatever
its visibility) hold every glyph the dashboard's labels use, in a fixed order, one per bucket
the dashboard's label sizes fall in. Every later glyph is then found in the atlas, never
packed after it, whatever the page drew meanwhile (docs/scenarios.md "Screenshots for CI").
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import viser

# viser's label bucket (label/LabelRenderer.tsx fontPxBucket): a screen label of scale s is
# rasterised at the power of two at or above max(8, 12 px * s * device pixel ratio).
SCREEN_EM_PX = 12.0
MIN_BUCKET_PX, MAX_BUCKET_PX = 8, 256
# One warm label per bucket the dashboard's label scales (0.58 .. 1.15) take at the 1.0
# device pixel ratio of the screenshots (tests/app/test_label_glyphs.py checks the scales).
WARM_SCALES = (0.5, 1.0)  # buckets 8 and 16

# What labels show: ASCII, Latin-1 (Italian captions, ° µ · « »), and the typography the
# dashboard's texts use. A glyph outside is packed after these, as before.
BASE_GLYPHS = "".join(
    [chr(c) for c in range(0x21, 0x7F)]
    + [chr(c) for c in range(0xA1, 0x100) if c != 0xAD]  # no soft hyphen: it has no ink
    + list("–—‘’“”…→←↑↓≠≤≥−"))


def bucket_px(scale: float, device_pixel_ratio: float = 1.0) -> int:
    """The atlas a screen label of ``font_screen_scale`` ``scale`` is drawn from."""
    px = min(MAX_BUCKET_PX, max(MIN_BUCKET_PX, SCREEN_EM_PX * scale * device_pixel_ratio))
    return int(2 ** math.ceil(math.log2(px)))


def glyph_order(extra: Iterable[str] = ()) -> str:
    """:data:`BASE_GLYPHS`, then the other visible characters of ``extra`` (scenario captions)
    by code point: one fixed order for a given input."""
    base = set(BASE_GLYPHS)
    more = {c for text in extra for c in text if not c.isspace() and c not in base}
    return BASE_GLYPHS + "".join(sorted(more))


def warm_glyphs(scene: viser.SceneApi, glyphs: str) -> list[viser.LabelHandle]:
    """The invisible labels holding ``glyphs``; they must be the scene's first labels."""
    return [scene.add_label(f"/glyphs/bucket{bucket_px(scale)}", glyphs, visible=False,
                            font_screen_scale=scale)
            for scale in WARM_SCALES]
