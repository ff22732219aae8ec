"""The Objects tab reads the dictionary every 2 s only while a browser is connected.

Each read is work for the simulation thread (which then keeps 1 ms naps for a while and moves
the rig's revision): a served rig nobody watches must not pay for it. The first browser to
connect gets a read at the next tick.
"""

from __future__ import annotations

from objects_tab_fakes import FakeRuntime, FakeServer

from app.ui.panels.object_dictionary import REFRESH_S, ObjectDictionaryPanel


def test_no_read_without_a_browser_then_one_at_the_first() -> None:
    server, runtime = FakeServer(), FakeRuntime()
    panel = ObjectDictionaryPanel(server, runtime, None, "fastcat")  # type: ignore[arg-type]
    for k in range(5):
        panel.tick(now=100.0 + k * REFRESH_S)
    assert runtime.reads == 0
    server.connect(1)
    panel.tick(now=100.0 + 5 * REFRESH_S)
    assert runtime.reads == 1
    panel.tick(now=100.0 + 5.5 * REFRESH_S)
    assert runtime.reads == 1  # every REFRESH_S, not every tick
    panel.tick(now=100.0 + 6 * REFRESH_S)
    assert runtime.reads == 2
