"""How many chunks a long recording writes (issue 7, "Soak: memory grows less than 10 MB").

rerun-sdk 0.41's file sink keeps a manifest entry for every chunk it writes until the file's
footer is written at the end (about 1 KB of the process's memory per chunk, measured on the
soak; docs/recording.md "Sampling and batching"), so the recorder must write few, long chunks
over a long session: each entity's rows go out when they fill a chunk, and the rest on a
period of minutes, not seconds. The count is read back from the file, and so is every row.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from test_recording import load, rows

from app.recording import RigRecorder
from devices.events import LogLine

S = 1_000_000
HOUR_US = 3600 * S
SAMPLE_US = 10_000  # the recorder's default sample period
# An hour of one drive moving at every sample and logging a line a second sends its position
# (100 rows/s) and its log (1 row/s): with one chunk per entity every 5 s that was about
# 1,450 chunks; a chunk per full buffer or per period is under 150.
MAX_CHUNKS = 150


def drive(i: int) -> dict[str, Any]:
    return {"rig": "soak", "devices": {"axis": {
        "kind": "servo", "position": float(i), "velocity": 12.5, "following_error": 0.25,
        "ds402_state": "OPERATION_ENABLED"}}}


def test_an_hour_of_a_moving_drive_is_few_chunks_and_every_row(tmp_path: Path) -> None:
    path = tmp_path / "hour.rrd"
    samples = HOUR_US // SAMPLE_US
    with RigRecorder(path, blueprint=False) as recorder:
        for i in range(samples):
            t = i * SAMPLE_US
            events = [LogLine(t, "axis", text=f"line {t // S}")] if t % S == 0 else []
            recorder.observe(t, drive(i), events)
    chunks = load(path)
    data = {p: [b for b in batches if "sim_time" in b.schema.names]
            for p, batches in chunks.items()}
    assert sum(len(b) for b in data.values()) <= MAX_CHUNKS, {p: len(b) for p, b in
                                                                data.items()}
    position = rows(chunks, "rig/axis/drive/position", "Scalars:scalars")
    assert position == [(i * SAMPLE_US, float(i)) for i in range(samples)]
    lines = rows(chunks, "rig/axis/events", "TextLog:text")
    assert [text for _, text in lines] == [f"line {s}" for s in range(3600)]
    assert [t for t, _ in lines] == [s * S for s in range(3600)]
    velocity = rows(chunks, "rig/axis/drive/velocity", "Scalars:scalars")
    assert velocity == [(0, 12.5), ((samples - 1) * SAMPLE_US, 12.5)]  # held to the end


def test_a_full_buffer_is_sent_at_once_and_the_buffer_stays_bounded(tmp_path: Path) -> None:
    """With a period longer than the run, entities still go out: each when it holds a chunk's
    worth of rows, and the fullest ones whenever all of them together hold the maximum."""
    path = tmp_path / "bounded.rrd"
    sent: list[int] = []

    class Spy(RigRecorder):
        def _send_buffers(self, hold: bool = False) -> None:
            sent.append(-1)
            super()._send_buffers(hold)

    with Spy(path, blueprint=False, flush_period_us=10 * HOUR_US, chunk_rows=500,
             max_buffered_rows=1_200) as recorder:
        most = 0
        for i in range(20_000):
            t = i * SAMPLE_US
            snap = drive(i)
            snap["devices"]["axis"]["velocity"] = float(i % 7)  # a second busy entity
            recorder.observe(t, snap, [LogLine(t, "axis", text=f"{i}")] if i % 3 == 0 else [])
            most = max(most, recorder.buffered_rows())
        assert most <= 1_200
    assert sent == [-1]  # only the close sent everything at once
    chunks = load(path)
    position = rows(chunks, "rig/axis/drive/position", "Scalars:scalars")
    assert [v for _, v in position] == [float(i) for i in range(20_000)]
    assert [v for _, v in rows(chunks, "rig/axis/drive/velocity", "Scalars:scalars")] == [
        float(i % 7) for i in range(20_000)]
    assert len(rows(chunks, "rig/axis/events", "TextLog:text")) == len(range(0, 20_000, 3))
    # Long chunks all the same: a full one (500 rows), or among the fullest when the three
    # entities held 1,200 rows together (at least 300 then), bar the last one, at close.
    batches = [b for b in chunks["rig/axis/drive/position"] if "sim_time" in b.schema.names]
    assert min(len(b) for b in batches[:-1]) >= 300, [len(b) for b in batches]
