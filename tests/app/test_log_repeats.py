"""Repeated retry lines collapse in both logs, so the root cause stays in view.

Seed 000 §7.1 / §7.7 has the trainee read "CoE - Emergency (Hex: ff00, 81, ...)" and "abnormal
state change ... with code 0x8204" in the logger. With module 2 unplugged in OP the master
retries every 2.14 s and prints two lines each time; before, the State tab's event log (50
rows) and the Line tab's master log (40 rows) held neither line ~48 s after the alarm. Now a
run of repeated rows is one row with a count and the last time (docs/dashboard.md), in the
format of the row's own stamp: "x3, last 14.55.23 915 ms", not "x3, last 119.1 s" (simulated
seconds next to a wall-clock stamp read as "119 s ago").
"""

from __future__ import annotations

import html
import re
from collections.abc import Iterator
from typing import Any

import pytest

from app.testing import RigSession, rig_session
from app.ui.line.master_panel import log_table
from app.ui.panels.event_log import EventLogPanel, LogRow, collapse_rows
from app.ui.repeats import collapse_repeats

FAILED = "'PREOP to SAFEOP' failed!"
ABORTED = "state change aborted (requested 'OP', back to 'PREOP')."


@pytest.fixture(scope="module")
def unplugged_60s() -> Iterator[RigSession]:
    """The default rig: the line in OP, module 2 unplugged, then 60 s of retries."""
    with rig_session() as rig:
        rig.command("fastcat", "power", on=True)
        rig.advance(4.0)
        rig.command("fastcat/2", "unplug")
        rig.advance(60.0)
        yield rig


def messages(table_html: str) -> list[str]:
    """The Message column of a log table, newest first."""
    return [html.unescape(m) for m in re.findall(r"<td>([^<]*)</td></tr>", table_html)]


def test_line_tab_log_keeps_the_root_cause(unplugged_60s: RigSession) -> None:
    log = unplugged_60s.snapshot("master")["log"]
    assert sum(FAILED in line["text"] for line in log) >= 27  # the retries are all there
    shown = messages(log_table(log))
    assert any("CoE - Emergency (Hex: ff00, 81" in m for m in shown), shown
    assert any("abnormal state change" in m and "0x8204" in m for m in shown), shown
    failed = [m for m in shown if FAILED in m]
    assert len(failed) == 1, shown
    # One row per run, with its count and the time of its last line, as its stamp reads
    # ("12/11/2019 14.52.34 645 ms"; the date left out, it is the first line's).
    count = sum(FAILED in line["text"] for line in log)
    last = [line["timestamp"] for line in log if FAILED in line["text"]][-1]
    assert failed[0].endswith(f" x{count}, last {last.split(' ', 1)[1]}"), failed[0]


def test_state_tab_event_log_keeps_the_root_cause(unplugged_60s: RigSession) -> None:
    panels = unplugged_60s.served.dashboard._panels
    assert panels is not None
    content = str(panels.log._html.content)
    shown = [html.unescape(m) for m in re.findall(
        r'<td class="fr-srv">.*?</td><td class="fr-ts">.*?</td><td>(.*?)</td>', content)]
    assert any("CoE - Emergency (Hex: ff00, 81" in m for m in shown), shown
    assert any("abnormal state change" in m for m in shown), shown
    assert any(m.startswith("Emergency sent (code 0xFF00") for m in shown), shown
    assert sum(FAILED in m for m in shown) == 1, shown
    assert sum(ABORTED in m for m in shown) == 1, shown
    assert re.search(r" x\d+, last \d\d\.\d\d\.\d\d \d{3} ms$",
                     next(m for m in shown if ABORTED in m))


def test_runs_of_one_or_several_lines_collapse_and_others_stay() -> None:
    key = str
    assert [(r.first, r.count) for r in collapse_repeats("EABABABC", key)] == [
        ("E", 1), ("A", 3), ("B", 3), ("C", 1)]
    assert [(r.first, r.count) for r in collapse_repeats("AAAB", key)] == [("A", 3), ("B", 1)]
    # A row between two equal ones is no repetition: order is kept, nothing is merged.
    assert [(r.first, r.count) for r in collapse_repeats("ACAD", key)] == [
        ("A", 1), ("C", 1), ("A", 1), ("D", 1)]
    runs = collapse_repeats([("x", 1.0), ("x", 3.0)], key=lambda item: item[0])
    assert runs[0].first == ("x", 1.0) and runs[0].last == ("x", 3.0)


def test_event_log_rows_of_other_servers_are_not_merged() -> None:
    def row(t: int, server: str, message: str) -> LogRow:
        return LogRow(t, t, server, f"ts{t}", message, False)

    rows = [row(1, "fastcat", "a"), row(2, "(65535)", "a"), row(3, "fastcat", "a"),
            row(4, "fastcat", "a")]
    out = collapse_rows(rows)  # oldest first in, newest first out
    assert [(r.server, r.message) for r in out] == [
        ("fastcat", "a x2, last ts4"), ("(65535)", "a"), ("fastcat", "a")]
    assert out[0].timestamp == "ts3"  # the run's first line: the Timestamp column stays ordered


class _Html:
    content = ""


class _Gui:
    def add_html(self, content: str) -> _Html:
        handle = _Html()
        handle.content = content
        return handle


class _Server:
    gui = _Gui()


def test_event_log_reads_the_master_log_beyond_its_rows() -> None:
    """The master's lines older than the last 50 count too: the emergency 60 lines back."""
    panel = EventLogPanel(_Server(), {}, lambda t_us: f"{t_us}")  # type: ignore[arg-type]
    lines: list[dict[str, Any]] = [{"t": 4.0, "port": 65535, "text": "CoE - Emergency"}]
    lines += [{"t": 5.0 + i, "port": 65535, "text": f"{FAILED} {ABORTED}",
               "timestamp": f"12/11/2019 14.{52 + i // 60}.{i % 60:02d} 000 ms"}
              for i in range(60)]
    panel.update({"log": lines})
    content = str(panel._html.content)
    assert "CoE - Emergency" in content and " x60, last 14.52.59 000 ms" in content


def test_the_last_time_reads_as_the_row_s_stamp() -> None:
    """The Timestamp column is the rig's wall clock (TwinCAT style): the last time of a run is
    printed the same way, the date only when it is not the first line's."""
    from app.ui.repeats import repeat_suffix

    first, last = "12/11/2019 14.53.24 815 ms", "12/11/2019 14.55.23 915 ms"
    assert repeat_suffix(3, first, last) == " x3, last 14.55.23 915 ms"
    assert repeat_suffix(2, first, "13/11/2019 00.00.01 000 ms") == (
        " x2, last 13/11/2019 00.00.01 000 ms")
    assert repeat_suffix(1, first, first) == ""
    # The master's plain style (no epoch): its stamp is simulated seconds, kept whole.
    assert repeat_suffix(4, "4.000 s", "10.420 s") == " x4, last 10.420 s"
    line = {"t": 4.0, "timestamp": first, "text": "a"}
    assert "a x2, last 14.53.26 815 ms" in log_table(
        [line, {**line, "t": 6.0, "timestamp": "12/11/2019 14.53.26 815 ms"}])
