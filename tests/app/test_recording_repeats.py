"""A live recorder repeats its last sample while the rig's revision stands (docs/recording.md
"Repeated samples"): the rows it sends are exactly those a fresh snapshot at every sample
gives.

Two recorders on one runtime, one repeating, one taking a snapshot at every sample, see the
same run: boot, idle stretches (the repeats), commands, and writes made the way protocol
adapters make them (model calls inside ``Runtime.call`` and ``Runtime.submit``, not rig
commands). Every row each one sends is compared.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from app.recording.recorder import RigRecorder, _Column, attach_to_runtime
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime

S = 1_000_000
WAIT_S = 120.0


class Capturing(RigRecorder):
    """A recorder that keeps a copy of every row it sends; ``repeat`` False: no repeats."""

    def __init__(self, path: Path, repeat: bool) -> None:
        super().__init__(path, blueprint=False)
        self.repeat = repeat
        self.repeats = 0
        self.sent: list[tuple[Any, ...]] = []

    def resample(self, t_us: int) -> bool:
        done = self.repeat and super().resample(t_us)
        self.repeats += done
        return done

    def _send_scalars(self, path: str, column: _Column, hold: bool = False) -> None:
        if hold:
            column.hold()
        self.sent.append(("scalars", path, list(column.times), list(column.values)))
        super()._send_scalars(path, column)

    def _send_buffers(self, hold: bool = False) -> None:
        for kind, columns in (("text", self._texts), ("lane", self._lanes)):
            for path, column in columns.items():
                if column.times:
                    self.sent.append((kind, path, list(column.times), list(column.values),
                                      list(column.levels)))
        super()._send_buffers(hold)


@pytest.fixture
def runtime() -> Iterator[Runtime]:
    rt = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    rt.set_paused(True)  # stepped by advance() only: the same run every time
    rt.start()
    yield rt
    rt.stop()


def advance(rt: Runtime, seconds: float) -> None:
    rt.advance(round(seconds * S)).result(timeout=WAIT_S)


def test_repeated_samples_are_the_samples_a_snapshot_gives(runtime: Runtime,
                                                           tmp_path: Path) -> None:
    repeating, snapping = Capturing(tmp_path / "a.rrd", True), Capturing(tmp_path / "b.rrd", False)
    for recorder in (repeating, snapping):
        attach_to_runtime(runtime, recorder)
    rig = runtime.rig
    drive, fastcat = rig.devices["drive"], rig.devices["fastcat"]
    runtime.command("fastcat", "power", {"on": True}).result(timeout=WAIT_S)
    advance(runtime, 8.0)  # the scan, the line to OP
    advance(runtime, 2.0)  # idle: repeats
    runtime.command("fastcat/2", "set_input", {"channel": 3, "value": True}).result(WAIT_S)
    advance(runtime, 1.0)
    # A protocol adapter's write: the model's own API inside call(), no rig command.
    runtime.call(lambda: drive.apply("enable", {"on": True}))
    advance(runtime, 0.5)
    runtime.call(lambda: drive.apply("jog", {"direction": 1}))
    advance(runtime, 1.0)
    runtime.call(lambda: drive.apply("stop", {}))
    advance(runtime, 2.0)
    runtime.submit(lambda: fastcat.apply("set_shaft_speed", {"encoder": 2, "rpm": 30.0},
                                         7)).result(WAIT_S)
    advance(runtime, 1.0)
    runtime.submit(lambda: fastcat.apply("set_shaft_speed", {"encoder": 2, "rpm": 0.0},
                                         7)).result(WAIT_S)
    advance(runtime, 1.0)
    runtime.command("fastcat", "inject_fault", {"fault": "MISSING_NODE_ANSWER"}).result(WAIT_S)
    advance(runtime, 1.5)
    runtime.command("fastcat", "clear_fault", {"fault": "MISSING_NODE_ANSWER"}).result(WAIT_S)
    advance(runtime, 2.0)
    runtime.stop()
    for recorder in (repeating, snapping):
        recorder.close()
    assert repeating.sent == snapping.sent
    # Not vacuous: the run moved the drive and the encoder, and most samples were repeats.
    moved = {path for kind, path, *_ in snapping.sent if kind == "scalars"}
    assert {"rig/drive/drive/position", "rig/fastcat/io/7/position"} <= moved
    assert repeating.repeats > 1_000 and snapping.repeats == 0


def test_calls_and_work_move_the_revision(runtime: Runtime) -> None:
    """What a protocol adapter runs in ``call`` or ``submit`` may write to any model: the
    revision moves, so no recorder repeats a sample across it."""
    rig = runtime.rig
    before = rig.revision
    runtime.call(lambda: None)
    assert rig.revision > before
    before = rig.revision
    runtime.submit(lambda: None).result(timeout=WAIT_S)
    assert rig.revision > before


def test_frames_keep_the_snapshots_of_models_nothing_moved(runtime: Runtime) -> None:
    """The publication takes a fresh snapshot only of the models whose snapshot may have
    moved: in an idle stretch the quiet ones are the same objects frame after frame, the
    master's (its frame counter) is new; a command makes every one new."""
    runtime.command("fastcat", "power", {"on": True}).result(timeout=WAIT_S)
    advance(runtime, 8.0)
    rig = runtime.rig
    quiet = [i for i, d in rig.devices.items() if d.QUIET_SNAPSHOT]
    assert set(quiet) == {"fastcat", "trscat", "cpx"}
    advance(runtime, 0.1)
    one = runtime.frame.snapshot["devices"]
    advance(runtime, 0.1)
    two = runtime.frame.snapshot["devices"]
    assert all(one[i] is two[i] for i in quiet)
    assert two["master"] is not one["master"]
    assert two["master"]["stats"]["frames"] > one["master"]["stats"]["frames"]
    runtime.command("cpx/1", "set_input", {"channel": 1, "on": True}).result(WAIT_S)
    advance(runtime, 0.1)
    three = runtime.frame.snapshot["devices"]
    assert not any(three[i] is two[i] for i in quiet)
    assert three == {i: d.snapshot() for i, d in rig.devices.items()}
