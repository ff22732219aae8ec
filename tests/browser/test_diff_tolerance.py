"""The screenshot comparison catches a changed text line (no browser: two pictures drawn here).

The dashboard's panel text is 13 px Liberation Sans (Debian's Arial / Helvetica) on a light
background, strokes one or two pixels wide. Drawn the same way on a 1280 x 720 page, one event
log line missing, added or replaced is 0.07-0.09 % of the pixels, one word of it changed
0.016 %: the old 1 % tolerance let all of them through, and the old one-way neighbourhood test
(a pixel differs when it differs from each baseline pixel around it) did not count text that
went away at all (a blank pixel always has a blank neighbour next to a thin stroke). A
picture that only moved by one pixel still passes.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import MAX_DIFF_FRACTION, diff_fraction
from PIL import Image, ImageDraw, ImageFont

FONT = Path("/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf")
PAGE = (1280, 720)
TEXT = (33, 37, 41)  # Mantine's text colour
LOG = [
    "ESM state change 'SAFEOP' -> 'OP'",
    "ESM state change 'PREOP' -> 'SAFEOP'",
    "CNF procedure: storing -> idle",
    "ESM state change 'INIT' -> 'PREOP'",
]


def page(lines: list[str], down: int = 0) -> Image.Image:
    """A page with ``lines`` as the dashboard's event log shows them, ``down`` px lower."""
    assert FONT.exists(), f"{FONT} is missing: Debian's fonts-liberation (bash .ci/setup --test)"
    font = ImageFont.truetype(str(FONT), 13)
    image = Image.new("RGB", PAGE, "white")
    draw = ImageDraw.Draw(image)
    for row, line in enumerate(lines):
        draw.text((190, 470 + down + row * 19), line, font=font, fill=TEXT)
    return image


@pytest.mark.parametrize("changed", [
    [*LOG[:1], "", *LOG[2:]],  # a line missing
    [*LOG[:1], "AL status code 0x8204", *LOG[2:]],  # a line replaced by a shorter one
    [*LOG, "ESM state change 'OP' -> 'PREOP'"],  # a line more
    ["ESM state change 'SAFEOP' -> 'PREOP'", *LOG[1:]],  # one word of a line changed
])
def test_a_changed_text_line_exceeds_the_tolerance(changed: list[str]) -> None:
    fraction, _ = diff_fraction(page(changed), page(LOG))
    assert fraction > MAX_DIFF_FRACTION, f"{fraction:.4%}"
    # either picture may be the baseline: a line that went away counts as one that came
    assert diff_fraction(page(LOG), page(changed))[0] == fraction


def test_a_picture_one_pixel_lower_passes() -> None:
    assert diff_fraction(page(LOG, down=1), page(LOG))[0] == 0.0
