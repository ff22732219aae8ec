"""The dashboard's CSS and small HTML helpers (one <style> element, injected once).

viser renders ``add_html`` content with innerHTML, so a <style> element placed in the first
panel styles every table of the dashboard. Class names carry an ``fr-`` prefix so they never
collide with viser's own (Mantine) classes.
"""

from __future__ import annotations

import functools
import html

CSS = """
<style>
/* viser's docked panels scroll in a Mantine ScrollArea whose vertical scrollbar lies over the
   content's right edge (--scrollarea-scrollbar-size, 11 px at 1280x720), and viser's HTML
   blocks, unlike its widgets and markdown, have no padding: the State tab's "zero-cycle
   alarm" ran under it. Every HTML block of ours (viser's <div> holding an element with an
   fr- class or id, neither one nor inside one) keeps that strip free, in every tab of both
   panels (tests/browser/test_panel_scrollbar.py). */
div:has(> :is([class^="fr-"], [class*=" fr-"], [id^="fr-"])):not(
    [class^="fr-"], [class*=" fr-"], [id^="fr-"],
    :is([class^="fr-"], [class*=" fr-"], [id^="fr-"]) div) {
  padding-right: var(--scrollarea-scrollbar-size, 12px); }
.fr-title { font-size: 0.9em; margin: 0 0 4px 0; }
.fr-kv { width: 100%; border-collapse: collapse; font-size: 0.82em; }
.fr-kv th { text-align: left; font-weight: 600; color: #555; padding: 2px 6px 2px 0;
            white-space: nowrap; vertical-align: top; width: 38%; }
.fr-kv td { padding: 2px 0; font-family: ui-monospace, Menlo, Consolas, monospace;
            vertical-align: top; word-break: break-word; }
.fr-badge { display: inline-block; padding: 0 6px; border-radius: 3px; font-weight: 700;
            font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-ok { background: #d9f2df; color: #1d6b32; }
.fr-bad { background: #fbd5d5; color: #a11616; }
.fr-warn { background: #fdefc3; color: #7a5600; }
.fr-muted { color: #888; }
.fr-next { color: #7a5600; }
.fr-nowrap { white-space: nowrap; }
.fr-log { width: 100%; border-collapse: collapse; font-size: 0.72em; table-layout: fixed;
          font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-log th { text-align: left; background: #eef0f3; color: #333; padding: 2px 4px;
             position: sticky; top: 0; font-family: system-ui, sans-serif; }
.fr-log td { padding: 2px 4px; border-bottom: 1px solid #eceef1; vertical-align: top;
             word-break: break-word; }
.fr-log td.fr-srv { color: #555; white-space: nowrap; overflow: hidden; }
.fr-log td.fr-ts { color: #555; white-space: nowrap; overflow: hidden; }
.fr-log tr.fr-err td { color: #a11616; }
.fr-log-wrap { max-height: 330px; overflow-y: auto; border: 1px solid #e3e5e8; }
.fr-od { width: 100%; border-collapse: collapse; font-size: 0.72em;
         font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-od th { text-align: left; background: #eef0f3; padding: 2px 4px; position: sticky; top: 0;
            font-family: system-ui, sans-serif; }
.fr-od td { padding: 1px 4px; border-bottom: 1px solid #eceef1; word-break: break-word; }
.fr-od td:nth-child(1), .fr-od td:nth-child(3), .fr-od td:nth-child(4) { white-space: nowrap; }
/* a one-cell row (no dictionary, no match) is the first cell too: its sentence wraps */
.fr-od td[colspan] { white-space: normal; }
.fr-od-wrap { max-height: 420px; overflow-y: auto; border: 1px solid #e3e5e8; }
</style>
"""


def esc(value: object) -> str:
    return _escaped(str(value))


# The views rebuild their HTML 30 times a second from mostly the same texts (labels, states,
# codes, the logs' visible rows): each is escaped once, not at every update. One update of the
# default rig escapes at most ~730 distinct texts, and 1,024 entries already hit as often as an
# unbounded cache; what more entries keep is one-off texts (new log rows' time stamps, ~42 per
# soak cycle), 8,192 of them ~2.7 MB (docs/performance.md "Session 19").
@functools.lru_cache(maxsize=2048)
def _escaped(text: str) -> str:
    return html.escape(text, quote=True)


def clock(seconds: float) -> str:
    """A title's simulated time, ``t = 12.3 s``, one unit: a long title (the Modbus drive's
    "served as Modbus TCP on :5020") broke it into "· t" and "= 116.3 s" on two lines."""
    return f'<span class="fr-muted fr-nowrap">t = {seconds:.1f} s</span>'


def badge(text: str, tone: str) -> str:
    """``tone`` is ok, bad, warn or muted."""
    return f'<span class="fr-badge fr-{tone}">{esc(text)}</span>'


# Rows and elements with this class are not shown on a trainee's page (the classroom's
# trainee CSS, app/ui/panels/classroom.py): what names an injected cause outright.
INSTRUCTOR_CLASS = "fr-instructor"
# Rows that name the simulator's injected causes, not anything the device shows.
CAUSE_ROWS = frozenset({"Causes", "Injected"})


def kv_table(rows: list[tuple[str, str]], table_id: str) -> str:
    """A two-column table; values are HTML already (escape them with :func:`esc`). A row
    of :data:`CAUSE_ROWS` is the instructor's (:data:`INSTRUCTOR_CLASS`)."""
    body = "".join(
        f'<tr class="{INSTRUCTOR_CLASS}"><th>{esc(k)}</th><td>{v}</td></tr>' if k in CAUSE_ROWS
        else f"<tr><th>{esc(k)}</th><td>{v}</td></tr>" for k, v in rows)
    return f'<table class="fr-kv" id="{esc(table_id)}">{body}</table>'
