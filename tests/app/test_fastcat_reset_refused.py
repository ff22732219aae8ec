"""A Reset fault the FastCAT refuses leaves a trace where the trainee looks: the event log.

Seed 000 §6.17 / §7: the rising edge of 0x5200:1 resets a resettable alarm only once its cause
is gone; with the cause present the coupler does nothing, and before, nothing on screen said
the reset was taken and refused (/tmp/s14/ui/06_reset_with_cause.png). The coupler's reaction
is unchanged; it now logs the refusal with its reason (a LogLine, as the servo drive's "alarm
reset refused"), and the State tab's event log shows the FastCAT's log lines.
"""

from __future__ import annotations

import html
import random
import re
from collections.abc import Iterator

import pytest
import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.panels.event_log import event_message
from devices.events import LogLine
from devices.fastcat.coupler import FastCat

TIMEOUT_S = 60
REFUSED = "Reset fault refused: alarm 0x04 MISSING_NODE_ANSWER module 2, cause still present"


def test_the_log_line_reads_as_an_error_row() -> None:
    line = LogLine(0, "fastcat", text=REFUSED)
    assert event_message(line, "fastcat") == (REFUSED, True)


def test_a_refused_reset_changes_nothing_but_is_logged() -> None:
    fc = FastCat("fastcat", random.Random(2), [("DB16", {}), ("DI16", {})])
    now = 0
    while not (fc.booted and fc.scan is None):
        now += 1_000
        fc.step(now)
    fc.apply("inject_fault", {"fault": "MISSING_NODE_ANSWER"}, 2)
    fc.step(now + 1_000)
    alarm = fc.alarm
    fc.drain_events()
    fc.apply("set_reset_fault", {"on": True})
    assert fc.alarm == alarm  # §7: the cause is present, the alarm stays
    lines = [e.text for e in fc.drain_events() if isinstance(e, LogLine)]
    assert lines == [REFUSED]
    fc.apply("set_reset_fault", {"on": True})  # no edge: not a reset, nothing logged
    assert not [e for e in fc.drain_events() if isinstance(e, LogLine)]


def log_rows(dashboard: Dashboard) -> list[tuple[str, str]]:
    assert dashboard._panels is not None
    content = str(dashboard._panels.log._html.content)
    return [(html.unescape(server), html.unescape(message)) for server, message in re.findall(
        r'<td class="fr-srv">(.*?)</td><td class="fr-ts">.*?</td><td>(.*?)</td>', content)]


@pytest.fixture
def dashboard() -> Iterator[tuple[Runtime, Dashboard]]:
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    runtime.set_paused(True)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    dash = Dashboard(server, runtime)  # ticked by the test
    runtime.start()
    try:
        yield runtime, dash
    finally:
        runtime.stop()
        server.stop()


def test_the_event_log_shows_the_refused_reset(dashboard: tuple[Runtime, Dashboard]) -> None:
    runtime, dash = dashboard
    runtime.advance(3_000_000).result(timeout=TIMEOUT_S)
    runtime.command("fastcat/2", "inject_fault", {"fault": "MISSING_NODE_ANSWER"}).result(
        timeout=TIMEOUT_S)
    runtime.advance(100_000).result(timeout=TIMEOUT_S)
    runtime.command("fastcat", "set_reset_fault", {"on": True}).result(timeout=TIMEOUT_S)
    runtime.advance(100_000).result(timeout=TIMEOUT_S)
    dash.tick()
    assert ("fastcat", REFUSED) in log_rows(dash), log_rows(dash)


def test_a_code_above_0x7f_is_refused_for_its_own_reason(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """§7: a coupler code above 0x7F needs a resync even with its cause gone."""
    from devices.fastcat.alarms import COUPLER_CODES, AlarmCode
    monkeypatch.setitem(COUPLER_CODES, 0x80, AlarmCode("coupler", 0x80, "TEST_FATAL", "test"))
    fc = FastCat("fastcat", random.Random(2), [("DB16", {})])
    now = 0
    while not (fc.booted and fc.scan is None):
        now += 1_000
        fc.step(now)
    fc.apply("inject_fault", {"fault": "coupler:0x80"})
    fc.step(now + 1_000)
    fc.apply("clear_fault", {"fault": "coupler:0x80"})
    fc.drain_events()
    fc.apply("set_reset_fault", {"on": True})
    assert fc.alarm is not None
    assert [e.text for e in fc.drain_events() if isinstance(e, LogLine)] == [
        "Reset fault refused: alarm 0x80 TEST_FATAL, not resettable (code above 0x7F): it "
        "needs a resync"]
