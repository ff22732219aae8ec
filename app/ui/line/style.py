"""CSS of the line's tables (added next to ``app.ui.style.CSS``)."""

LINE_CSS = """
<style>
#fr-line-slaves td { font-size: 0.95em; }
/* A badge ("power off", "SAFEOP -> OP") wraps between its words, never inside one. */
#fr-line-slaves .fr-badge { overflow-wrap: normal; word-break: normal; }
#fr-line-log td { white-space: pre-wrap; }
.fr-line-bad { color: #a11616; font-weight: 600; }
.fr-line-warn { color: #7a5600; font-weight: 600; }
/* The master's Phase badge is one word or two ("no slave answers"): never split. */
#fr-line-master-status .fr-badge { white-space: nowrap; }
#fr-slave-leds, #fr-slave-io, #fr-slave-diag { margin-top: 6px; }
</style>
"""
