"""No panel text runs under a panel's scrollbar, at the browser tests' 1280 x 720.

viser's docked panels scroll in a Mantine ScrollArea whose vertical scrollbar lies over the
right edge of the content (an overlay, about 11 px wide), and viser's HTML blocks have no
padding of their own: the review found the State tab's Causes row of ax2_zero_mark_missing
reading "zero-cycle alarm" with its last letters under the scrollbar (and before, the Alarm
row's "coupler"), the Line tab's log and the Codes tab's answer too. Every text of every tab
of both panels is measured as Chromium lays it out: its right edge must stay left of the
scrollbar's strip (its left edge when shown, else where it would show), and no word of it
may break inside (the room taken from the text must not cut a code or a name in two).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from helpers import LiveDashboard, open_dashboard, wait_until

from app.scenario import load_scenario

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[2]
BOOT_S = 8.0

# For each docked panel's scroll viewport: how many texts it shows, the words whose right
# edge passes the scrollbar's strip, and the words the layout breaks over two lines inside.
UNDER_BAR_JS = """
() => {
  const panels = [];
  for (const vp of document.querySelectorAll('.mantine-ScrollArea-viewport')) {
    const box = vp.getBoundingClientRect();
    if (box.width < 200 || box.height < 50) continue;  // a dropdown's list, not a panel
    const root = vp.closest('.mantine-ScrollArea-root');
    const bar = [...root.querySelectorAll(':scope > .mantine-ScrollArea-scrollbar')]
      .find(s => s.dataset.orientation === 'vertical' && s.getBoundingClientRect().width > 0);
    // A panel that does not overflow shows no bar: the strip is where it comes once it does.
    const probe = document.createElement('div');
    probe.style.width = 'var(--scrollarea-scrollbar-size)';
    root.appendChild(probe);
    const size = probe.getBoundingClientRect().width;
    probe.remove();
    const edge = bar ? bar.getBoundingClientRect().left
                     : box.left + vp.clientLeft + vp.clientWidth - size;
    const under = [], split = [];
    let texts = 0;
    const walker = document.createTreeWalker(vp, NodeFilter.SHOW_TEXT);
    for (let node = walker.nextNode(); node; node = walker.nextNode()) {
      if (!node.data.trim() || node.parentElement.closest('style')) continue;
      const range = document.createRange();
      range.selectNodeContents(node);
      const rects = [...range.getClientRects()].filter(r => r.width > 0 && r.height > 0);
      if (!rects.length) continue;  // not shown (a closed folder, a hidden row)
      texts += 1;
      // Word by word: a space that ends a line of a pre-wrap cell hangs past it, unseen.
      const words = /\\S+/g;
      let m;
      while ((m = words.exec(node.data)) !== null) {
        const word = document.createRange();
        word.setStart(node, m.index);
        word.setEnd(node, m.index + m[0].length);
        const right = Math.max(...[...word.getClientRects()].map(r => r.right));
        if (right > edge + 0.5) {
          under.push(`${m[0]} in ${node.data.trim().slice(0, 60)}`
                     + ` (right ${right.toFixed(1)} > ${edge.toFixed(1)})`);
        }
      }
      // A break after a hyphen ("Pre-" / "operational") is a line's, not inside a word.
      const pieces = /[^\\s-]+/g;
      while ((m = pieces.exec(node.data)) !== null) {
        const piece = document.createRange();
        piece.setStart(node, m.index);
        piece.setEnd(node, m.index + m[0].length);
        const tops = new Set([...piece.getClientRects()].filter(r => r.width > 0)
                                                        .map(r => Math.round(r.top)));
        if (tops.size > 1) split.push(m[0]);
      }
    }
    panels.push({left: Math.round(box.left), texts, under, split});
  }
  return panels;
}
"""


def _every_tab(page: Any) -> dict[str, list[dict[str, Any]]]:
    """Each tab of both panels shown in turn, and what :data:`UNDER_BAR_JS` finds then."""
    found: dict[str, list[dict[str, Any]]] = {}
    tabs = page.get_by_role("tab").all()
    assert len(tabs) >= 8, "the default rig's panels have their tabs"
    for number, tab in enumerate(tabs):
        name = f"{number} {tab.inner_text().strip()}"
        tab.click()
        wait_until(lambda tab=tab: tab.get_attribute("aria-selected") == "true", what=name)
        page.wait_for_timeout(300)  # the tab's HTML mounted and laid out
        found[name] = page.evaluate(UNDER_BAR_JS)
    return found


def _check(found: dict[str, list[dict[str, Any]]]) -> None:
    for tab, panels in found.items():  # the left panel and the control panel, each with text
        assert {p["left"] < 100 for p in panels if p["texts"]} == {True, False}, (tab, panels)
    under = {f"{tab} @x={p['left']}": p["under"] for tab, panels in found.items()
             for p in panels if p["under"]}
    split = {f"{tab} @x={p['left']}": p["split"] for tab, panels in found.items()
             for p in panels if p["split"]}
    assert under == {}, "texts under the scrollbar's strip"
    assert split == {}, "words broken inside"


def test_default_rig_panels_keep_clear_of_the_scrollbar(live: LiveDashboard,
                                                        page: Any) -> None:
    open_dashboard(page, live)
    live.advance(BOOT_S)  # the line in OP, the master's log with its long lines
    _check(_every_tab(page))


def test_ax2_zero_mark_panels_keep_clear_of_the_scrollbar(live: LiveDashboard,
                                                          page: Any) -> None:
    """static/scenarios/ax2_zero_mark_missing.toml at its checkpoint zero_cycle_alarm
    (7.5 s), played by the dashboard's own player: the Causes row's "zero-cycle alarm"."""
    scenario = load_scenario(ROOT / "static" / "scenarios" / "ax2_zero_mark_missing.toml")
    open_dashboard(page, live)
    panel = live.dashboard.scenario_player
    panel.load(scenario)
    while live.runtime.frame.t_us < 7_500_000:
        panel.player.step()
    live.settle()
    wait_until(lambda: "ENC1_ZERO_CYCLE" in page.locator("#fr-state").inner_text(),
               what="the zero-cycle alarm in the State tab")
    _check(_every_tab(page))


TOKEN = "scrollbar-token"
LOADED_S = 60.0  # a page on a machine loaded by other test runs can take long to come up


def test_classroom_panels_keep_clear_of_the_scrollbar(tmp_path: Path, browser: Any) -> None:
    """The instructor's and a trainee's page of a served rig with an exercise running: the
    Classroom folder's boards and the instructor-only rows too (docs/classroom.md)."""
    from helpers import VIEWPORT, choose, close_webgl_toast, free_port, wait_for_text

    from app.classroom.roles import Access
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.ui.panels.classroom_rig import serve_rig

    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path / "state")
    served = serve_rig(rig, Access(TOKEN), port=free_port(), record=tmp_path / "session.rrd",
                       paused=True)
    contexts = []
    try:
        served.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        served.runtime.advance(round(BOOT_S * 1_000_000)).result(timeout=30)
        pages = {}
        for role, query in (("instructor", f"?token={TOKEN}&fixedDpr=1"),
                            ("trainee", "?fixedDpr=1")):
            context = browser.new_context(viewport=VIEWPORT, device_scale_factor=1)
            contexts.append(context)
            page = pages[role] = context.new_page()
            page.goto(served.url + query)
            close_webgl_toast(page, timeout=LOADED_S)
            wait_for_text(page, f"You are {'the' if role == 'instructor' else 'a'} {role}",
                          timeout=LOADED_S)
        choose(pages["instructor"], "Hidden fault", "fastcat: inject coupler 0x04")
        pages["instructor"].get_by_role("button", name="Start exercise").click()
        wait_until(lambda: served.classroom.exercise is not None, what="the exercise")
        served.runtime.advance(1_000_000).result(timeout=30)
        status = pages["trainee"].locator("#fr-exercise-trainee")
        wait_until(lambda: status.get_attribute("data-phase") == "running",
                   what="the trainee sees the exercise")
        for page in pages.values():
            _check(_every_tab(page))
    finally:
        for context in contexts:
            context.close()
        served.stop()


def test_the_objects_tab_without_a_dictionary_keeps_clear_of_the_scrollbar(
        live: LiveDashboard, page: Any) -> None:
    """The FastCAT off: the Objects tab's one-cell row says why there is no dictionary. CI
    once caught the tab before its first read and the sentence ran 480 px past the panel: the
    cell is the row's first and took the Index:Sub column's no-wrap."""
    open_dashboard(page, live)
    live.runtime.command("fastcat", "power", {"on": False}).result(timeout=10)
    live.advance(1.0)
    page.get_by_role("tab", name="Objects").click()
    wait_until(lambda: "no object dictionary now" in page.locator("#fr-od").inner_text(),
               what="the Objects tab's no-dictionary row")
    _check(_every_tab(page))
