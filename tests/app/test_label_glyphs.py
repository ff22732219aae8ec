"""The glyph order of the 3D labels (app/ui/glyphs.py): the warm labels come first, cover
every atlas the dashboard's labels are drawn from and every character their texts hold.

The pictures themselves are compared in tests/browser/test_screenshot_bytes.py; this checks,
without a browser, that a label added to the dashboard later does not fall outside the warm
set (a new label size in another bucket, a text with a new character).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import ServedRig
from app.ui.glyphs import BASE_GLYPHS, WARM_SCALES, bucket_px, glyph_order

RIGS = sorted(DEFAULT_RIG.parent.glob("*.toml"))


@pytest.fixture
def labels(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[tuple[str, str, float]]]:
    """(name, text, font_screen_scale) of every label added, in order."""
    added: list[tuple[str, str, float]] = []
    real = viser.SceneApi.add_label

    def add_label(self: viser.SceneApi, name: str, text: str, **kwargs: Any) -> Any:
        added.append((name, text, kwargs.get("font_screen_scale", 1.0)))
        return real(self, name, text, **kwargs)

    monkeypatch.setattr(viser.SceneApi, "add_label", add_label)
    yield added


def dashboard_labels(rig_file: Path, added: list[tuple[str, str, float]],
                     texts: tuple[str, ...] = ()) -> list[tuple[str, str, float]]:
    served = ServedRig.start(build_rig(load_rig_spec(rig_file)), quiet=True, texts=texts)
    try:
        served.advance(0.5)  # the first frame's texts too
    finally:
        served.stop()
    return added


@pytest.mark.parametrize("rig_file", RIGS, ids=[p.stem for p in RIGS])
def test_warm_labels_come_first_and_cover_every_label(
        rig_file: Path, labels: list[tuple[str, str, float]]) -> None:
    added = dashboard_labels(rig_file, labels)
    warm = added[:len(WARM_SCALES)]
    assert [name.startswith("/glyphs/") for name, _t, _s in warm] == [True] * len(WARM_SCALES)
    assert {text for _n, text, _s in warm} == {BASE_GLYPHS}
    warm_buckets = {bucket_px(scale) for scale in WARM_SCALES}
    assert len(warm_buckets) == len(WARM_SCALES)  # one label per atlas, none twice
    rest = added[len(WARM_SCALES):]
    assert rest, "the dashboard made no label"
    for name, text, scale in rest:
        assert bucket_px(scale) in warm_buckets, f"{name} (scale {scale}): a bucket not warmed"
        outside = sorted({c for c in text if not c.isspace()} - set(BASE_GLYPHS))
        assert not outside, f"{name} {text!r}: characters not warmed: {outside}"


def test_a_scenario_s_own_characters_follow_the_base_set_in_code_point_order() -> None:
    order = glyph_order(["Zero cycle: 1,5 giri → allarme ✓", "Ω ✓"])
    assert order == BASE_GLYPHS + "Ω✓"
    assert glyph_order([]) == BASE_GLYPHS
    assert len(set(BASE_GLYPHS)) == len(BASE_GLYPHS)


def test_bucket_is_viser_s_power_of_two() -> None:
    # label/LabelRenderer.tsx fontPxBucket: 12 px em, at least 8, rounded up to 2^n
    assert [bucket_px(s) for s in (0.5, 0.58, 0.66, 0.67, 1.0, 1.15, 1.34)] == \
        [8, 8, 8, 16, 16, 16, 32]
    assert bucket_px(1.0, device_pixel_ratio=2.0) == 32
