"""Scene nodes that send only what changed: LED colours and label texts, cached per key.

Shared by the bodies of the line (``app.ui.line.bodies``): every frame asks for the colour of
every LED at the frame's simulated time, but only flips reach the browsers.
"""

from __future__ import annotations

from typing import Any

import viser

from app.ui.rail_scene import LED_OFF, LIT, RGB, led_lit

# The CPX-E-EC's Run / Error also light orange (seed 002 tables 11-13).
COLOURS: dict[str, RGB] = {**LIT, "orange": (255, 128, 0)}
FRONT_Y = -1.06  # the front plane of the line's bodies (their depth is 2.0, like the rail)


def lit_colour(colour: str, pattern: str, t_us: int) -> RGB:
    return COLOURS.get(colour, COLOURS["green"]) if led_lit(pattern, t_us) else LED_OFF


class Painter:
    """Scene nodes under ``root``, with caches of the colours and texts last sent."""

    def __init__(self, server: viser.ViserServer, root: str) -> None:
        self.scene = server.scene
        self.root = root
        self._colours: dict[str, RGB] = {}
        self._texts: dict[str, str] = {}
        self.leds: dict[str, viser.BoxHandle] = {}
        self.labels: dict[str, viser.LabelHandle] = {}

    def box(self, name: str, size: tuple[float, float, float], at: tuple[float, float, float],
            colour: RGB, **kw: Any) -> viser.BoxHandle:
        return self.scene.add_box(f"{self.root}/{name}", color=colour, dimensions=size,
                                  position=at, **kw)

    def label(self, key: str, text: str, at: tuple[float, float, float], *,
              anchor: str = "center-left", scale: float = 0.7) -> viser.LabelHandle:
        handle = self.scene.add_label(f"{self.root}/{key}", text, position=at,
                                      anchor=anchor,  # type: ignore[arg-type]
                                      font_screen_scale=scale)
        self.labels[key] = handle
        self._texts[key] = text
        return handle

    def led(self, key: str, at: tuple[float, float, float],
            size: tuple[float, float, float] = (0.3, 0.12, 0.2)) -> viser.BoxHandle:
        safe = key.replace(" ", "_").replace("/", "_").replace("+", "p")
        handle = self.box(f"led_{safe}", size, at, LED_OFF)
        self.leds[key] = handle
        self._colours[key] = LED_OFF
        return handle

    def set_led(self, key: str, colour: str, pattern: str, t_us: int) -> None:
        handle = self.leds.get(key)
        if handle is None:
            return
        rgb = lit_colour(colour, pattern, t_us)
        if self._colours.get(key) != rgb:
            handle.color = rgb
            self._colours[key] = rgb

    def set_text(self, key: str, text: str) -> None:
        handle = self.labels.get(key)
        if handle is not None and self._texts.get(key) != text:
            handle.text = text
            self._texts[key] = text

    def colours(self) -> dict[str, RGB]:
        return dict(self._colours)

    def text(self, key: str) -> str:
        return self._texts.get(key, "")
