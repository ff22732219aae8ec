"""What a buffered sample row costs (issue 7, "Soak: memory grows less than 10 MB").

The recorder holds rows for minutes before it sends them (a chunk per entity per 4,096 rows or
per 5 minutes, test_recording_chunks.py), up to 20,000 rows in all: kept as Python objects (an
int per time, a tuple of floats per row) that was ~120 bytes a row and most of the soak's early
growth. Scalar rows are kept as machine numbers: 8 bytes a time and 8 per value, plus the
arrays' spare room. Measured with tracemalloc: what the buffers release when they are taken.
"""

from __future__ import annotations

import gc
import tracemalloc
from pathlib import Path
from typing import Any

from app.recording import RigRecorder

SAMPLE_US = 10_000
SAMPLES = 3_000  # under a chunk (4,096 rows) and the period: everything stays buffered
SPARE = 1.15  # an array grows by ~1/8 of its size at a time
PER_COLUMN = 256  # the arrays' headers


def moving(i: int) -> dict[str, Any]:
    return {"rig": "soak", "devices": {"axis": {
        "kind": "servo", "position": float(i), "velocity": float(i % 5),
        "following_error": i / 7, "ds402_state": "OPERATION_ENABLED"}}}


def test_a_buffered_scalar_row_costs_machine_numbers_only(tmp_path: Path) -> None:
    recorder = RigRecorder(tmp_path / "b.rrd", blueprint=False)
    tracemalloc.start()
    try:
        for i in range(SAMPLES):
            recorder.observe(i * SAMPLE_US, moving(i), [])
        columns = list(recorder._scalars.values())
        rows = sum(len(c.times) for c in columns)
        limit = sum(SPARE * 8 * (1 + c.width) * len(c.times) + PER_COLUMN for c in columns)
        gc.collect()
        before = tracemalloc.get_traced_memory()[0]
        for column in columns:
            column.take()  # what the buffers held is released here
        gc.collect()
        held = before - tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
        recorder.close()
    assert rows >= 2 * SAMPLES  # position and following error change at every sample
    assert held <= limit, f"{held / rows:.0f} bytes a row, limit {limit / rows:.0f}"
