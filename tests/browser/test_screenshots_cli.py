"""Headless screenshots for CI: one PNG per checkpoint plus events.jsonl, the same twice.

static/scenarios/module_lost_in_op.toml (seed 000 §7.7) has three checkpoints: op (5.2 s),
in_alarm (7 s), recovered (15.5 s). Two runs must give the same pictures within the browser
tests' tolerance, and events.jsonl must be the lines ``scenario run`` prints.
"""

from __future__ import annotations

import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
from helpers import MAX_DIFF_FRACTION, diff_fraction
from PIL import Image

from app.out_paths import event_lines
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario, run_scenario
from app.screenshots import ScreenshotRun, image_name, run_with_screenshots
from app.testing import fieldrig  # noqa: F401  (the plugin's fixture, as users get it)
from app.ui.panels.scenario_player import STATUS_ID

pytestmark = pytest.mark.browser

SCENARIO = DEFAULT_RIG.parent.parent / "scenarios" / "module_lost_in_op.toml"
NAMES = ["01-op.png", "02-in_alarm.png", "03-recovered.png"]
# The baselines' 0.01 % (tests/browser/shots.py): the CLI's pictures have the 3D canvas on
# whole pixels as the baselines do (app/whole_pixels.py). Before, it was 1 %: viser's 672.64 px
# canvas, which Chromium sometimes stretched by a fraction of a pixel (0.25-0.49 % of the
# pixels, docs/dashboard.md "Browser tests").
RUNS_MAX_DIFF_FRACTION = MAX_DIFF_FRACTION
# OP and in alarm differ by far more than a few LEDs' worth of pixels
CHANGED_MIN_FRACTION = 0.01
ROOT = Path(__file__).resolve().parents[2]


def reference_lines() -> str:
    scenario = load_scenario(SCENARIO)
    return event_lines(run_scenario(scenario, build_rig(load_rig_spec(DEFAULT_RIG))).events)


def shoot(out: Path) -> ScreenshotRun:
    """One run, in a thread of its own: Playwright's sync API refuses to start a second time
    in a thread that already runs it (the session's ``browser`` fixture of other tests)."""
    scenario = load_scenario(SCENARIO)
    with ThreadPoolExecutor(1) as pool:
        run = pool.submit(run_with_screenshots, scenario,
                          build_rig(load_rig_spec(DEFAULT_RIG)), out).result(timeout=600)
    assert not run.failures
    assert [p.name for p in run.images] == NAMES
    return run


def test_two_runs_give_the_same_pictures_and_the_events_of_scenario_run(tmp_path: Path) -> None:
    runs = shoot(tmp_path / "a"), shoot(tmp_path / "b")
    first, second = runs[0].images, runs[1].images
    for a, b in zip(first, second, strict=True):
        with Image.open(a) as one, Image.open(b) as two:
            assert one.size == (1280, 720)
            fraction, _ = diff_fraction(one, two)
        assert fraction <= RUNS_MAX_DIFF_FRACTION, f"{a.name}: {fraction:.4%} of the pixels differ"
    # The pictures show the rig as it changes: OP and in alarm are not the same image.
    with Image.open(first[0]) as op, Image.open(first[1]) as alarm:
        assert diff_fraction(op, alarm)[0] > CHANGED_MIN_FRACTION
    expected = reference_lines()
    for run in runs:
        assert event_lines(run.events) == expected
    # The pictures only: events.jsonl is the CLI's (test_the_command_line).
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == NAMES


@pytest.mark.parametrize(("number", "name", "file"), [
    (1, "op", "01-op.png"), (12, "in alarm / 2", "12-in_alarm_2.png"), (3, "../x", "03-x.png"),
    (4, "", "04-checkpoint.png")])
def test_image_names_are_file_safe(number: int, name: str, file: str) -> None:
    assert image_name(number, name) == file


def test_the_command_line(tmp_path: Path) -> None:
    """``python -m app scenario run FILE --out DIR --screenshots`` (the CLI hook, app/cli.py)."""
    out = tmp_path / "cli"
    done = subprocess.run([sys.executable, "-m", "app", "scenario", "run", str(SCENARIO),
                           "--out", str(out), "--screenshots", "--quiet"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "viser" not in done.stdout + done.stderr  # --quiet: no banner, no "Server stopped"
    assert sorted(p.name for p in out.iterdir()) == [*NAMES, "events.jsonl"]
    assert (out / "events.jsonl").read_text(encoding="utf-8") == reference_lines()


# ---- app.testing: the helper users import in their own tests (README example) ---------------
def readme_example(tmp_path: Path) -> Path:
    """The README's example test, run as written (its own asserts): a copy of it here went
    on passing whatever the README said."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    (code,) = [b for b in re.findall(r"^```python\n(.*?)^```", readme, re.M | re.S)
               if "rig_session" in b]
    names: dict[str, Any] = {}
    exec(compile(code, "README.md", "exec"), names)
    tests = [f for name, f in names.items() if name.startswith("test_")]
    assert len(tests) == 1
    tests[0](tmp_path)
    return tmp_path / "alarm.png"


def test_rig_session_as_in_the_readme(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)  # the README's paths are relative to the checkout
    with ThreadPoolExecutor(1) as pool:  # a Playwright of its own (see shoot())
        picture = pool.submit(readme_example, tmp_path).result(timeout=300)
    with Image.open(picture) as image:
        assert image.size == (1280, 720)


def test_fieldrig_fixture_and_play(fieldrig) -> None:  # noqa: F811 (the imported fixture)
    rig = fieldrig()
    failures = rig.play(SCENARIO)
    assert failures == [] and rig.t == load_scenario(SCENARIO).end_us / 1e6
    checkpoints = [e.to_record()["name"] for e in rig.events("checkpoint")]
    assert checkpoints == ["op", "in_alarm", "recovered"]


def test_the_comparison_forgives_a_one_pixel_shift_but_not_a_changed_led() -> None:
    """The CI failure of 2026-11-22 in miniature: the same picture one pixel lower passes; a
    green LED turned red (a few pixels) is still counted."""
    from PIL import Image, ImageDraw

    base = Image.new("RGB", (200, 100), "white")
    draw = ImageDraw.Draw(base)
    draw.rectangle((20, 20, 180, 80), outline="black", width=1)
    draw.ellipse((90, 40, 100, 50), fill=(0, 200, 0))
    shifted = Image.new("RGB", base.size, "white")
    shifted.paste(base, (0, 1))
    assert diff_fraction(shifted, base)[0] == 0.0
    red = base.copy()
    ImageDraw.Draw(red).ellipse((90, 40, 100, 50), fill=(220, 0, 0))
    fraction, mask = diff_fraction(red, base)
    assert fraction > 0.003 and mask.getpixel((95, 45)) == 255


# ---- a rig without tabs: the player folder sits below the others ----------------------------
NINE_ANALOG = DEFAULT_RIG.parent / "nine_analog.toml"
TOO_MANY_ANALOG = DEFAULT_RIG.parent.parent / "scenarios" / "too_many_analog.toml"
# Is the element on screen and not covered or scrolled out of its panel: the page's topmost
# element at a point near its top and near its bottom is the element or inside it.
SHOWN_JS = """el => { const r = el.getBoundingClientRect();
  if (r.height === 0 || r.width === 0) return false;
  const x = r.left + Math.min(r.width / 2, 40);
  return [r.top + 2, r.bottom - 2].every(y => { const at = document.elementFromPoint(x, y);
    return at !== null && (el === at || el.contains(at)); }); }"""
# The status block is rewritten with every frame of a paused rig (its data-frame marker): a
# locator's element can be replaced between Playwright resolving it and evaluating on it (a
# detached node, no box). Found and measured in one task instead.
STATUS_SHOWN_JS = f"id => ({SHOWN_JS})(document.getElementById(id))"


def player_on_screen_at_checkpoints() -> list[tuple[str, bool, bool]]:
    """(checkpoint, player folder title shown, status shown) as the screenshot run has the
    page at each checkpoint of too_many_analog on the nine_analog rig (no control tabs)."""
    from app.screenshots import Chromium, play, served_run

    seen: list[tuple[str, bool, bool]] = []
    rig = build_rig(load_rig_spec(NINE_ANALOG))
    with served_run(rig, quiet=True) as (served, _events), Chromium() as browser:
        page = browser.open(served, show_player=True)

        def look(step: Any) -> None:
            page.sync()
            title = page.page.get_by_text("Scenario player", exact=True).first
            seen.append((step.text, bool(title.evaluate(SHOWN_JS)),
                         bool(page.page.evaluate(STATUS_SHOWN_JS, STATUS_ID))))

        assert play(served, load_scenario(TOO_MANY_ANALOG), rig, look) == []
        page.close()
    return seen


def test_screenshots_show_the_player_on_a_rig_without_tabs() -> None:
    """docs/scenarios.md: the pictures show the scenario player (scenario, time, step,
    caption). On nine_analog the control panel has no tabs and the "Scenario player" folder
    comes after Power, Faults, Modules: below the fold of a 720 px page unless brought up."""
    with ThreadPoolExecutor(1) as pool:  # a Playwright of its own (see shoot())
        seen = pool.submit(player_on_screen_at_checkpoints).result(timeout=300)
    assert seen == [("max_analog_alarm", True, True)]
