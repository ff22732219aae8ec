"""Everything a recording holds, chunk by chunk, against a stored digest (docs/recording.md
"Cost per sample").

The recorder's per-sample work is tuned for speed (a sample runs 100 times a simulated
second); a change for speed must not change what is recorded. Two short deterministic runs
of the default rig are recorded and read back with the SDK's reader (what a viewer loads):
a jammed drive (motion, an alarm, events) through ``scenario_observer`` as
``scenario run --record`` records, and a module lost in OP through a hook that repeats the
last sample while the rig's revision stands, as a served rig is recorded ("Repeated
samples"). Small chunk and buffer sizes make the runs send chunks of every kind on the way.

Each entity becomes a line for its static rows (series names, colours, lane styles) and
one for its rows on the timeline (the rows of each chunk sent, and a hash of every column's
values and times in order); each blueprint chunk a line. Row ids, log times, the wall-clock
start time and the blueprint's random view ids are left out. The lines are compared with
``recording_content.golden``: a dropped, renamed or added entity, a changed value, time,
series name, style or blueprint, or rows sent in other chunks fail, and the message names
the entities. When a change of content is meant, rewrite the digest and say so in the commit:

    python -m tests.app.test_recording_content --write
"""

from __future__ import annotations

import hashlib
import re
import sys
import tempfile
import uuid
from collections import defaultdict
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from rerun.chunk import RrdReader

from app.recording import RigRecorder, scenario_observer
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario, run_scenario
from devices.events import Event

GOLDEN = Path(__file__).with_name("recording_content.golden")
SCENARIOS = Path(__file__).resolve().parents[2] / "static" / "scenarios"
# Small sizes: full-chunk sends, the buffer limit and periodic flushes all happen in 14 s.
SIZES = {"chunk_rows": 300, "max_buffered_rows": 2_000, "flush_period_us": 3_000_000}
# Columns that differ from run to run whatever the recorder does.
UNSTABLE = {"rerun.controls.RowId", "log_time", "RecordingInfo:start_time"}
ROOT = "ViewportBlueprint:root_container"
UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")

Hook = Callable[[Rig, list[Event]], None]


def repeating_observer(recorder: RigRecorder) -> Hook:
    """attach_to_runtime's per-step hook without a runtime's threads: a sample due while the
    revision stands repeats the last one; the step's events go with it, as a batch would."""
    sampled = [-1]

    def on_tick(rig: Rig, events: list[Event]) -> None:
        if recorder.al_status is None:
            scenario_observer(recorder)(rig, [])  # the same set-up (and first sample)
            sampled[0] = rig.revision
        t_us = rig.clock.now_us
        if not recorder.sample_due(t_us):
            if events:
                recorder.observe(t_us, None, events)
            return
        if not events and rig.revision == sampled[0] and recorder.resample(t_us):
            return
        sampled[0] = rig.revision
        recorder.observe(t_us, rig.snapshot(), events)

    return on_tick


def record(scenario: str, observer: Callable[[RigRecorder], Hook], path: Path) -> Path:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    recorder = RigRecorder(path, recording_id=scenario, **SIZES)
    run_scenario(load_scenario(SCENARIOS / f"{scenario}.toml"), rig,
                 on_tick=observer(recorder))
    recorder.close()
    return path


def _digest(value: object) -> str:
    return hashlib.sha256(repr(value).encode()).hexdigest()[:16]


def entity_lines(path: Path) -> Iterator[str]:
    """The recording's entities by path, each one line for its static rows and one for its
    rows on the timeline: how many chunks with how many rows each, and a hash of every
    column's values in file order. Entities come by path, not in file order: rerun's batcher
    writes the static rows (``log``) beside the sent columns in an order, and in chunks, that
    depend on its wall-clock flushes."""
    reader = RrdReader(str(path))
    # Static rows by component: the batcher puts an entity's static rows in one chunk or in
    # several, as its flushes fall.
    static: dict[str, dict[str, list[object]]] = defaultdict(lambda: defaultdict(list))
    temporal: dict[str, list[object]] = defaultdict(list)
    chunks: dict[str, list[int]] = defaultdict(list)
    for store in reader.recordings():
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            columns = sorted((name, batch.column(name).to_pylist())
                             for name in batch.schema.names if name not in UNSTABLE)
            if chunk.is_static:
                for name, values in columns:  # a merged chunk's other rows are nulls here
                    static[chunk.entity_path][name].extend(v for v in values if v is not None)
            else:
                temporal[chunk.entity_path].append(columns)
                chunks[chunk.entity_path].append(batch.num_rows)
    for entity in sorted(static.keys() | temporal.keys()):
        if entity in static:
            yield f"recording {entity} static {_digest(sorted(static[entity].items()))}"
        if entity in temporal:
            sizes = ",".join(map(str, chunks[entity]))
            yield f"recording {entity} temporal {sizes} {_digest(temporal[entity])}"


def blueprint_lines(path: Path) -> list[str]:
    """The blueprint's chunks, sorted (rerun writes them in no fixed order), each random view
    or container id replaced by what it stands for (a view's title, a container's title or
    contents)."""
    reader = RrdReader(str(path))
    chunks = []
    for store in reader.blueprints():
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            columns = {name: batch.column(name).to_pylist() for name in batch.schema.names
                       if name not in UNSTABLE}
            if ROOT in columns:  # the root container's id, as bytes: spelled as the others
                columns[ROOT] = [str(uuid.UUID(bytes=bytes(row[0]))) for row in columns[ROOT]]
            chunks.append((chunk.entity_path, columns))
    names = _blueprint_names(chunks)

    def stable(text: str) -> str:
        return UUID.sub(lambda m: names.get(m.group(0), "<unnamed>"), text)

    return sorted(f"blueprint {stable(entity)} {_digest(stable(repr(sorted(columns.items()))))}"
                  for entity, columns in chunks)


def _blueprint_names(chunks: list[tuple[str, dict[str, list[Any]]]]) -> dict[str, str]:
    names: dict[str, str] = {}
    for path, columns in chunks:
        found = UUID.search(path)
        title = columns.get("ViewBlueprint:display_name")
        if found and path.startswith("/view/") and title:
            names[found.group(0)] = f"view {title!r}"
    containers = [(UUID.search(path).group(0), columns) for path, columns in chunks
                  if path.startswith("/container/") and UUID.search(path)]
    for _ in range(len(containers) + 1):  # named from the leaves up
        for view_id, columns in containers:
            if view_id in names:
                continue
            title = columns.get("ContainerBlueprint:display_name")
            contents = [UUID.search(c) for c in
                        (columns.get("ContainerBlueprint:contents") or [[]])[0]]
            if title:
                names[view_id] = f"container {title!r}"
            elif all(c and c.group(0) in names for c in contents):
                names[view_id] = \
                    f"container [{', '.join(names[c.group(0)] for c in contents)}]"
    return names


RUNS = (("drive_jammed_load", scenario_observer), ("module_lost_in_op", repeating_observer))


def content(tmp: Path, runs: tuple[tuple[str, Callable[[RigRecorder], Hook]], ...] = RUNS
            ) -> list[str]:
    lines: list[str] = []
    for scenario, observer in runs:
        lines.append(f"# {scenario}")
        path = record(scenario, observer, tmp / f"{scenario}.rrd")
        lines.extend(entity_lines(path))
        lines.extend(blueprint_lines(path))
    return lines


def entities(lines: list[str]) -> set[str]:
    return {line.split()[1] for line in lines if line.startswith("recording ")}


def golden(scenario: str | None = None) -> list[str]:
    """The stored lines, or those of one run's recording."""
    lines = GOLDEN.read_text().splitlines()
    if scenario is None:
        return lines
    start = lines.index(f"# {scenario}")
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("#")),
               len(lines))
    return lines[start:end]


def test_recorded_content_is_unchanged(tmp_path: Path) -> None:
    got = content(tmp_path)
    want = golden()
    missing, extra = entities(want) - entities(got), entities(got) - entities(want)
    assert not missing and not extra, f"entities missing: {sorted(missing)[:20]}, " \
                                      f"new: {sorted(extra)[:20]}"
    changed = [f"{w}  !=  {g}" for w, g in zip(want, got, strict=False) if w != g]
    assert len(got) == len(want) and not changed, \
        f"{len(want)} lines stored, {len(got)} now; first differences: {changed[:10]}"


def test_the_digest_sees_a_dropped_signal(tmp_path: Path, monkeypatch) -> None:
    """The digest is not blind: with one drive's velocity gone from its snapshots, that
    entity is reported missing (and its plot's blueprint lines differ)."""
    snapshot = Rig.snapshot

    def without_velocity(rig: Rig) -> dict:
        snap = snapshot(rig)
        snap["devices"]["drive"].pop("velocity", None)
        return snap

    monkeypatch.setattr(Rig, "snapshot", without_velocity)
    got = content(tmp_path, RUNS[:1])
    want = golden(RUNS[0][0])
    assert entities(want) - entities(got) == {"/rig/drive/drive/velocity"}
    assert entities(got) <= entities(want)
    changed = set(got) - set(want)  # the velocity plot is gone from the drive's tab
    assert changed and all(line.startswith("blueprint /container/") for line in changed)


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python -m tests.app.test_recording_content --write")
    with tempfile.TemporaryDirectory() as tmp:
        GOLDEN.write_text("\n".join(content(Path(tmp))) + "\n")
    print(f"wrote {GOLDEN}")
