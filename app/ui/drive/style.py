"""CSS of the drive and CANopen tabs (one <style> element, injected once with the tabs).

Added next to the dashboard's own CSS (``app.ui.style``), whose ``fr-kv`` / ``fr-badge`` classes
the drive tabs reuse. The bit grids and the frame log are drive-only, hence a second element;
class names keep the ``fr-`` prefix.
"""

from __future__ import annotations

DRIVE_CSS = """
<style>
.fr-bits { width: calc(100% - 10px); border-collapse: separate; border-spacing: 2px;
           table-layout: fixed; font-size: 0.68em; margin: 0 0 4px 0; }
.fr-bits td { padding: 1px 3px; border-radius: 3px; background: #eef0f3; color: #8a8f98;
              vertical-align: top; line-height: 1.2; overflow: hidden; }
.fr-bits td.fr-on { background: #d9f2df; color: #1d6b32; font-weight: 700; }
.fr-bits td.fr-on.fr-alert { background: #fbd5d5; color: #a11616; }
.fr-bits td b { font-family: ui-monospace, Menlo, Consolas, monospace; margin-right: 3px; }
.fr-bits caption { text-align: left; font-size: 1.25em; color: #333; padding: 0 0 1px 2px;
                   caption-side: top; }
.fr-bits caption span { font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-frames { width: 100%; border-collapse: collapse; table-layout: fixed; font-size: 0.68em;
             font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-frames th { text-align: left; background: #eef0f3; padding: 1px 3px; position: sticky;
                top: 0; font-family: system-ui, sans-serif; }
.fr-frames td { padding: 1px 3px; border-bottom: 1px solid #eceef1; vertical-align: top;
                word-break: break-word; }
/* The time column holds "1234.567" on one line (5.4em): a number broken after five
   characters ("10.25" / "0") read as two values. */
.fr-frames td.fr-t { white-space: nowrap; }
.fr-frames tr.fr-rx td { color: #1f4f8f; }
.fr-frames tr.fr-emcy td { color: #a11616; }
/* Repeated heartbeats: one line each above the log (canopen_panel.heartbeat_html). */
.fr-hb { font-size: 0.68em; margin: 0 0 3px 0; color: #555;
         font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-frames-wrap { max-height: 300px; overflow-y: auto; border: 1px solid #e3e5e8; }
.fr-pdo { width: 100%; border-collapse: collapse; font-size: 0.68em;
          font-family: ui-monospace, Menlo, Consolas, monospace; }
.fr-pdo th { text-align: left; background: #eef0f3; padding: 1px 3px;
             font-family: system-ui, sans-serif; }
.fr-pdo td { padding: 1px 3px; border-bottom: 1px solid #eceef1; word-break: break-word; }
.fr-pdo tr.fr-off td { color: #9aa0a8; }
.fr-note { font-size: 0.82em; margin: 2px 0 6px 0; }
.fr-drive-log { font-size: 0.7em; font-family: ui-monospace, Menlo, Consolas, monospace;
                margin: 0; padding: 0; list-style: none; }
.fr-drive-log li { border-bottom: 1px solid #eceef1; padding: 1px 0; }
.fr-drive-log li.fr-err { color: #a11616; }
</style>
"""
