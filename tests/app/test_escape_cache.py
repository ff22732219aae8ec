"""The HTML escape cache (app/ui/style.py) is large enough for what the dashboard escapes.

The cache pays only for texts that come back update after update (labels, states, the logs'
visible rows); a text that shows once (a new log row's time stamp) is a miss whatever the
cache's size, and a larger cache only keeps more of those: 8,192 of them were ~2.7 MB in the
soak (docs/hardening.md "Soak"). Too small, it would miss the texts every update shows again
(256 entries: 28 % of the soak's escapes missed, docs/performance.md "Session 19"). Checked on
the served default rig with a page connected (its own views drawn too): over the line's
power-up and its first seconds in OP the cache misses no more often than an unbounded one
would (each distinct text once).
"""

from __future__ import annotations

import pytest
from served_dashboard import drawn, served_default_rig
from viser_page import Page, wait

from app.ui import style


def test_the_cache_misses_each_text_once_over_a_watched_run(
        monkeypatch: pytest.MonkeyPatch) -> None:
    cache = style._escaped
    cache.cache_clear()  # what other tests escaped would hide this run's misses
    texts: set[str] = set()

    def counted(text: str) -> str:
        texts.add(text)
        return cache(text)

    monkeypatch.setattr(style, "_escaped", counted)
    with served_default_rig(0.0) as live:
        page = Page(live.server.get_port())
        try:
            wait(lambda: live.server.get_clients())
            for device_id, info in live.runtime.rig.describe().items():  # as `python -m app`
                if "power" in info["actions"]:
                    live.command(device_id, "power", {"on": True})
            for _ in range(40):  # the line to OP and 5 s in it, the logs filling
                live.advance(0.2)
                drawn(live)
        finally:
            page.close()
    info = cache.cache_info()
    assert info.hits > 10 * len(texts) > 3000  # the views escaped the same texts again
    assert info.misses <= len(texts) + 10  # each text missed once (a few by two threads)
