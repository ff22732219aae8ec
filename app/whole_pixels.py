"""The 3D canvas on whole CSS pixels before a picture: the `--screenshots` CLI
(app/screenshots.py) and the browser tests' baselines (tests/browser/shots.py) both call
:func:`pin_3d_canvas`.

viser's title bar is 47.36 px high, so the 3D canvas below it is 672.64 CSS px high over a
672 px drawing buffer, and Chromium's compositor sometimes stretched that buffer over the
fraction and sometimes not: 3 of 49 browser test runs (2 under load) had the whole 3D view
stretched by 0.64 px from top to bottom (0.25-0.49 % of the pixels, all on edges;
docs/dashboard.md "Browser tests"). A title bar of whole pixels leaves nothing to stretch; the
canvas follows (viser's resize observer) and its drawing buffer with the next frame drawn.
"""

from __future__ import annotations

from typing import Any

# The 3D canvas is the one with a drawing buffer (an empty 0 x 0 canvas of viser's lies over
# it). The title bar is the sibling before the outermost element that starts where the canvas
# starts. A page laid out otherwise (a viser upgrade) throws: no picture of an unpinned canvas.
PIN_JS = """() => {
  const fail = what => { throw new Error(`the page's layout changed: ${what}`); };
  const canvas = [...document.querySelectorAll('canvas')].find(c => c.width > 300);
  if (!canvas) fail('no 3D canvas');
  let area = canvas;
  while (area.parentElement
         && area.parentElement.getBoundingClientRect().top === canvas.getBoundingClientRect().top)
    area = area.parentElement;
  const bar = area.previousElementSibling;
  if (!bar) fail('no title bar above the 3D canvas');
  bar.style.height = Math.round(bar.getBoundingClientRect().height) + 'px';
  bar.style.flex = '0 0 auto';
}"""
# Drawing buffer and CSS box agree (device pixel ratio 1) and start on a pixel
PINNED_JS = """() => {
  const canvas = [...document.querySelectorAll('canvas')].find(c => c.width > 300);
  const box = canvas.getBoundingClientRect();
  return canvas.width === box.width && canvas.height === box.height
         && Number.isInteger(box.top) && Number.isInteger(box.left);
}"""


def pin_3d_canvas(page: Any, timeout_s: float) -> None:
    """Round the title bar above the 3D canvas of ``page`` (a Playwright page) to whole pixels
    and wait until the canvas's drawing buffer matches its box. Idempotent: once pinned, the
    bar stays pinned and the wait returns at once. Playwright's error when the page is laid
    out otherwise or the canvas does not follow within ``timeout_s``."""
    page.evaluate(PIN_JS)
    page.wait_for_function(PINNED_JS, timeout=timeout_s * 1000)
