"""The snippet of docs/recording.md "Reading a recording from Python" gives the events in order.

A support engineer copies it to read a customer's recording. Its paragraph says that a sort
keeping the order of equal times keeps the events' order, but the snippet sorted the
(time, text) pairs whole: equal-time lines came out in alphabetical order (at 1 ms the master's
"[port 65535] ... distributed clocks" line before its four "slave N (100N): INIT" lines,
which the event log has first).
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

from test_recording import Run

from app.recording import event_text

DOC = Path(__file__).resolve().parents[2] / "docs" / "recording.md"


def snippet() -> str:
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## Reading a recording from Python", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)  # type: ignore[union-attr]


def test_the_snippet_prints_the_first_master_events_in_their_order(tmp_path: Path) -> None:
    run = Run(tmp_path / "demo.rrd")
    run.hook(run.rig, run.rig.take_events())
    run.run_until(200_000)
    run.recorder.close()
    code = snippet().replace('"out/demo.rrd"', repr(str(run.path)))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, str(DOC), "exec"), {})
    master = [e for e in run.events if e.device == "master"][:5]
    assert len({e.t_us for e in master}) < len(master)  # equal times: the order matters
    expected = [(e.t_us / 1e6, event_text.text(e, e.to_record(), run.recorder.al_status))
                for e in master]
    assert out.getvalue().strip() == repr(expected)
