"""What the runtime's journal costs per event beyond the event itself (issue 7, "Soak: memory
grows less than 10 MB"). The journal keeps the last JOURNAL_LENGTH events for the views that
read it incrementally (``events_since``); their sequence numbers are consecutive, so an entry
needs no (seq, event) tuple nor an int of its own: ~90 bytes an event, ~1.8 MB for a full
journal, was what the soak's hour grew by beside the events. Measured with tracemalloc on a
runtime that is not started (``_journal_events`` is what the simulation thread calls)."""

from __future__ import annotations

import gc
import tracemalloc

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import JOURNAL_LENGTH, Runtime
from devices.events import LogLine

PER_EVENT = 16  # a deque slot is 8 bytes, plus its blocks' links


def test_a_journalled_event_costs_a_slot_and_reads_back_in_order() -> None:
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    events = [LogLine(i, "dev", text="x") for i in range(JOURNAL_LENGTH + 500)]
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for i in range(0, len(events), 100):  # batches, as steps journal them
            runtime._journal_events(events[i:i + 100])
        gc.collect()
        held = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert held <= PER_EVENT * JOURNAL_LENGTH, f"{held / JOURNAL_LENGTH:.0f} bytes an event"
    last, kept = runtime.events_since(0)
    assert last == len(events) and kept == events[-JOURNAL_LENGTH:]  # the oldest dropped
    assert runtime.events_since(last - 3) == (last, events[-3:])
    assert runtime.events_since(last) == (last, [])
    assert runtime.events_since(100) == (last, events[-JOURNAL_LENGTH:])  # fell out: all kept
