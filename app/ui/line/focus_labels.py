"""A scenario's focused view hides the labels its edges would cut.

A label keeps its size on screen whatever the zoom (viser "screen" labels), so in a view
zoomed on one device the neighbours' labels ran past the picture's border: "ble 0", "INK-ACT
OUT flickering", half a header, half of the axis caption. A scenario's focus moves every
browser's camera to one pose (app/ui/line/view.py), so the scene, which every browser shares,
can be fitted to it: while that focus holds, a label whose background is not wholly inside
the view of the dashboard's 1280 x 720 layout is hidden; every other label stays, the
neighbours' included, so the picture keeps what it can show whole. The labels come back when
the focus ends: "Show the whole line" for every page, a new focus, or one page's own move
(a click on a device, its "Show the whole line"), after which the browsers no longer share a
view. Labels rebuilt or retexted meanwhile are fitted each frame.
"""

from __future__ import annotations

import threading
from typing import Any

import viser

from app.ui.label_fit import View, handle_rect, inside

EDGE_PX = 4.0  # the panels' borders take a few pixels of the view
FITS_KEPT = 4096  # layouts remembered per view (a moving carriage's label makes new ones)
# Not fitted: the caption is placed for the view by the dashboard, the glyph labels are never
# shown (app/ui/glyphs.py).
KEEP = ("/caption", "/glyphs/")


class FocusLabels:
    """The labels of ``server``'s scene hidden for a shared focused view."""

    def __init__(self, server: viser.ViserServer, width_px: float, height_px: float,
                 fov: float) -> None:
        self._server = server
        self._size = (width_px, height_px)
        self.fov = fov
        self._view: View | None = None
        self._hidden: dict[str, Any] = {}  # node name -> the handle this hid
        self._fits: dict[tuple[Any, ...], bool] = {}  # per view: label layout -> inside
        # A click's release runs in viser's thread, the frame's refresh in the dashboard's.
        self._lock = threading.Lock()

    def view(self, position: tuple[float, float, float],
             look_at: tuple[float, float, float]) -> View:
        """The layout's view from ``position`` looking at ``look_at``."""
        return View(position, look_at, self.fov, *self._size)

    def focus(self, view: View) -> None:
        """Every browser shares ``view``: hide what it cuts."""
        with self._lock:
            self._view = view
            self._fits = {}
        self.refresh()

    def release(self) -> None:
        """The browsers no longer share the focused view: every hidden label back."""
        with self._lock:
            self._view = None
            self._fits = {}
            labels = self._labels()
            for name, handle in self._hidden.items():
                if labels.get(name) is handle:
                    handle.visible = True
            self._hidden = {}

    def refresh(self) -> None:
        """Fit the labels as they are now (texts change, a rebuilt slot brings new ones)."""
        with self._lock:
            view = self._view
            if view is None:
                return
            if len(self._fits) > FITS_KEPT:
                self._fits = {}
            labels = self._labels()
            self._hidden = {n: h for n, h in self._hidden.items() if labels.get(n) is h}
            for name, handle in labels.items():
                hidden = name in self._hidden
                if not hidden and not handle.visible:
                    continue  # its owner's: not ours to show
                fits = self._fit(view, handle)
                if fits and hidden:
                    handle.visible = True
                    del self._hidden[name]
                elif not fits and not hidden:
                    handle.visible = False
                    self._hidden[name] = handle

    def hidden(self) -> list[str]:
        """The labels hidden now, by node name (tests)."""
        return sorted(self._hidden)

    def _fit(self, view: View, handle: Any) -> bool:
        key = (str(handle.text), tuple(float(v) for v in handle.position), str(handle.anchor),
               handle.font_size_mode, float(handle.font_screen_scale),
               float(handle.font_scene_height))
        fits = self._fits.get(key)
        if fits is None:
            # an empty label draws nothing that could be cut
            fits = not key[0] or inside(handle_rect(view, handle), view, EDGE_PX)
            self._fits[key] = fits
        return fits

    def _labels(self) -> dict[str, Any]:
        # viser 1.1.1 (pinned) lists no scene nodes publicly; its registry is what browsers get.
        nodes = self._server.scene._handle_from_node_name
        return {name: handle for name, handle in list(nodes.items())
                if isinstance(handle, viser.LabelHandle) and not name.startswith(KEEP)}
