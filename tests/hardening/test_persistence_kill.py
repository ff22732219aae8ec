"""A process killed at random points during flash writes leaves the old or the new content.

Issue 7 "Hardening", persistence: a real subprocess (flash_child.py) stores the FastCAT
configuration (CNF, seed 000 §2) or saves the drive (0x3802 = 0x0011, seed 004 ch.2) into an
app.flash_file.FileFlash again and again; this test kills it with SIGKILL, most times a random
0-5 ms after it announced a write, sometimes at any moment. After each kill the file must load
without error and hold the content of the last completed write or of the write that was under
way (only the new one once that write was reported done); the next process started on the file
must load that content into the device and accept it. Rounds per device: 4 in CI, 60 with
``--full``. A random kill rarely lands inside a sub-millisecond write, so each step of the
write is also killed on purpose (the child stops itself there: flash_child.STOP_POINTS).
"""

from __future__ import annotations

import json
import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from flash_child import STOP_POINTS, content_value, digest

from app.flash_file import FileFlash

HERE = Path(__file__).resolve().parent
CHILD = HERE / "flash_child.py"
SEED = 99
KILL_INSIDE_WRITE = 0.75  # share of rounds killed just after a "begin"
READY_TIMEOUT_S = 120.0  # wall time for a child to start and announce (a loaded CI machine)


class Child:
    def __init__(self, kind: str, path: Path, *stop_at: str) -> None:
        self.proc = subprocess.Popen([sys.executable, str(CHILD), kind, str(path), *stop_at],
                                     cwd=HERE.parents[1], stdout=subprocess.PIPE, text=True)
        self.lines: list[dict[str, Any]] = []

    def next(self) -> dict[str, Any]:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            raise AssertionError(f"the child ended (code {self.proc.poll()}) without a line")
        event = json.loads(line)
        self.lines.append(event)
        return event

    def kill(self) -> None:
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(READY_TIMEOUT_S)
        assert self.proc.stdout is not None
        for line in self.proc.stdout:  # what it printed before it died
            if line.strip():
                try:
                    self.lines.append(json.loads(line))
                except json.JSONDecodeError:
                    break  # a line cut by the kill: the write it announced is not known done


def _allowed(start_sha: str, lines: list[dict[str, Any]]) -> set[str]:
    """The contents the file may hold after the kill."""
    done, under_way = start_sha, None
    for event in lines:
        if event["event"] == "begin":
            under_way = event["sha"]
        elif event["event"] == "end":
            done, under_way = event["sha"], None
    return {done} if under_way is None else {done, under_way}


@pytest.mark.parametrize("kind", ["fastcat", "drive"])
def test_killed_writer_leaves_old_or_new_content(kind: str, full: bool, tmp_path: Path) -> None:
    rng = random.Random(SEED)
    path = tmp_path / f"{kind}.flash"
    values: dict[str, Any] = {"none": None}  # content hash -> what the content says
    on_disk = "none"
    kills_inside = 0
    for round_no in range(60 if full else 4):
        child = Child(kind, path)
        loaded = child.next()
        # the device loaded what the file holds, and accepted it
        assert loaded["event"] == "loaded" and loaded["sha"] == on_disk, (round_no, loaded)
        assert not loaded["alarm"], (round_no, loaded)
        if on_disk != "none":
            assert loaded["value"] == values[on_disk], (round_no, loaded, values[on_disk])
        if rng.random() < KILL_INSIDE_WRITE:
            wanted = rng.randint(1, 3)
            begins = 0
            while begins < wanted:
                event = child.next()
                if event["event"] == "begin":
                    begins += 1
                    values[event["sha"]] = event["value"]
            time.sleep(rng.uniform(0, 0.005))
            kills_inside += 1
        else:
            time.sleep(rng.uniform(0, 0.4))
        child.kill()
        for event in child.lines:
            if event["event"] == "begin":
                values[event["sha"]] = event["value"]
        payload = FileFlash(path).load()  # raises CorruptFlash on a broken file
        on_disk = digest(payload)
        assert on_disk in _allowed(loaded["sha"], child.lines[1:]), (round_no, on_disk)
        if payload is not None:
            assert content_value(kind, payload) == values[on_disk]
    assert kills_inside > 0


@pytest.mark.parametrize("point", STOP_POINTS)
@pytest.mark.parametrize("kind", ["fastcat", "drive"])
def test_killed_at_each_step_of_a_write(kind: str, point: str, tmp_path: Path) -> None:
    """The kill lands exactly at one step of FileFlash.save (the child stops itself there):
    before the temporary file is synced or renamed the file holds the old content, from the
    rename on the new one; either way it loads and the next process accepts it. A first write
    (no file before) and a second one (an old content to keep) are both killed."""
    path = tmp_path / f"{kind}.flash"
    for first in (True, False):
        before = digest(FileFlash(path).load())
        assert (before == "none") is first
        child = Child(kind, path, point)
        loaded = child.next()
        assert loaded["event"] == "loaded" and loaded["sha"] == before
        begin = child.next()
        assert begin["event"] == "begin"
        assert child.next() == {"event": "stopped", "at": point}
        child.kill()
        on_disk = digest(FileFlash(path).load())
        expected = before if point != "fsync_dir" else begin["sha"]
        assert on_disk == expected, (point, first)
        if point != "fsync_dir":  # the file kept the old content: write the new one for real
            writer = Child(kind, path)
            assert writer.next()["sha"] == before
            while writer.next()["event"] != "end":
                pass
            writer.kill()
        # read before the next process starts: once it has loaded the file it writes the other
        # content at once, and on a busy machine it could finish before the test read it
        now = digest(FileFlash(path).load())
        after = Child(kind, path)
        loaded = after.next()  # the next process loads the file and accepts it
        assert loaded["sha"] == now and not loaded["alarm"]
        after.kill()
