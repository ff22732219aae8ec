"""The streaming benchmark's clients are counted as pages: viser 1.1.1 lists a connection in
``get_clients()`` only after its first camera message (a browser's viewer sends one at once),
and the dashboard draws nothing while that list is empty (docs/dashboard.md "Threading"). A
client that only listened measured an idle rig streaming nothing."""

from __future__ import annotations

from bench._stream_clicks import measure
from bench.streaming import listen, start_server


def test_a_client_receives_the_idle_rigs_blinking_leds() -> None:
    server = start_server(motion=False, probe=False)
    try:
        tally = listen(server.port, 1, 0.5, 1.5)[0]
    finally:
        server.close()
    assert tally.frames > 5 and tally.messages > 20  # LED colours: ~150 a second


def test_the_clicking_case_counts_the_clicks_and_both_pages() -> None:
    server = start_server(motion=False, probe=False)
    try:
        result = measure(server.port, "this", 1, 1.5, 0.5)
    finally:
        server.close()
    assert result.clicks >= 5
    (idle, clicking), = result.watcher
    assert idle.messages > 20 and clicking.messages > 20
    assert result.clicker[0].messages > 20
