"""The process test_persistence_kill.py kills: a device saving to a FileFlash, over and over.

    python tests/hardening/flash_child.py fastcat|drive PATH

At start it prints what the device loaded from PATH (``loaded``: the payload's hash, what the
device made of it — its stored configuration or its d1 — and whether it refused it), then
saves new content in a loop, alternating two contents:

- fastcat: CNF held 3 s (seed 000 §2: reset, scan, store the detected configuration), with the
  last module taken off the rail or put back between two stores (and before the first one when
  the flash already holds the full rail, so that every write changes the content);
- drive: parameter d1 set to 20 or 30 (the other value than the one loaded), then the save
  command 0x3802 = 0x0011 (seed 004 ch.2 "Salvataggio su flash"), stepped until it completes.

Around each write of the flash file it prints ``begin`` (with the hash of the content about to
be written) and ``end``. Nothing else: the parent reads these lines and kills the process with
SIGKILL at random points, most of them inside a write.

    python tests/hardening/flash_child.py fastcat|drive PATH STEP

With STEP (one of STOP_POINTS), the first write stops the process at that step of
FileFlash.save (after printing ``stopped``): the parent's SIGKILL then lands exactly there, a
moment a random kill of a sub-millisecond write rarely hits.
"""

from __future__ import annotations

import hashlib
import json
import os
import random
import signal
import sys
from collections.abc import Callable
from typing import Any

from app.flash_file import FileFlash
from devices.fastcat.coupler import FastCat
from devices.servo.drive import DriveConfig, ServoDrive

STEP_US = 1_000
RAIL = [("DB16", {}), ("DI16", {}), ("AI8D", {})]
SAVE_COMMAND, SAVE_VALUE = 0x3802, 0x0011
D1 = 1  # parameter d1, address 1


def digest(data: bytes | None) -> str:
    return "none" if data is None else hashlib.sha256(data).hexdigest()[:16]


def say(**fields: Any) -> None:
    print(json.dumps(fields), flush=True)


class TracedFlash(FileFlash):
    """The real FileFlash; the lines only mark where its write starts and ends."""

    def __init__(self, path: str, kind: str) -> None:
        super().__init__(path)
        self.kind = kind

    def save(self, data: bytes) -> None:
        say(event="begin", sha=digest(data), value=content_value(self.kind, data))
        super().save(data)
        say(event="end", sha=digest(data))


def content_value(kind: str, data: bytes) -> Any:
    """What the content says: the stored module names, or the drive's d1."""
    decoded = json.loads(data)
    return decoded if kind == "fastcat" else decoded["parameters"]["d1"]


def run_fastcat(flash: TracedFlash) -> None:
    fc = FastCat("fastcat", random.Random(1), RAIL, flash=flash)
    say(event="loaded", sha=digest(flash.load()), value=fc.stored, alarm=fc.alarm is not None)
    t = 0
    if fc.stored == [name for name, _options in RAIL]:
        fc.apply("unplug", {}, len(RAIL))  # the first store writes the other content
    while True:
        release = t + 3_000_000
        fc.apply("hold_cnf", {"seconds": 3.0})
        while not (t > release and fc.snapshot()["cnf"]["phase"] == "idle"):
            t += STEP_US
            fc.step(t)
        last = len(RAIL)
        if fc.rail[last - 1] is not None:
            fc.apply("unplug", {}, last)
        else:
            fc.apply("plug", {"type": RAIL[-1][0]}, last)


def run_drive(flash: TracedFlash) -> None:
    drive = ServoDrive("servo", random.Random(1), DriveConfig(), flash)
    rejected = any("flash content rejected" in getattr(e, "text", "")
                   for e in drive.drain_events())
    value = drive.read_parameter(D1)
    say(event="loaded", sha=digest(flash.load()), value=value, alarm=rejected)
    t = 100_000
    drive.step(t)  # past the power-on self test
    while True:
        value = 50 - value  # 20, 30, 20, ...
        drive.write_parameter(D1, value)
        drive.write_parameter(SAVE_COMMAND, SAVE_VALUE)
        while drive.saving:
            t += 10 * STEP_US
            drive.step(t)


# The steps of FileFlash.save, each named by the call it is about to make: the temporary file
# written but not synced; synced, not yet renamed over the flash file; renamed, the directory
# not yet synced.
STOP_POINTS = ("fsync_file", "replace", "fsync_dir")


def stop_before(point: str) -> None:
    """Make the first write stop the process just before the call named ``point``."""
    fsync, replace = os.fsync, os.replace
    calls = {"fsync": 0}

    def stopped(name: str, call: Callable[..., None]) -> Callable[..., None]:
        def run(*args: object) -> None:
            if name == point:
                say(event="stopped", at=point)
                os.kill(os.getpid(), signal.SIGSTOP)  # the parent kills it here
            call(*args)
        return run

    def fsync_either(fd: int) -> None:
        calls["fsync"] += 1  # the first fsync is the file's, the second the directory's
        name = "fsync_file" if calls["fsync"] == 1 else "fsync_dir"
        stopped(name, fsync)(fd)

    os.fsync = fsync_either
    os.replace = stopped("replace", replace)


def main() -> None:
    kind, path = sys.argv[1], sys.argv[2]
    if len(sys.argv) > 3:
        stop_before(sys.argv[3])
    flash = TracedFlash(path, kind)
    (run_fastcat if kind == "fastcat" else run_drive)(flash)


if __name__ == "__main__":
    main()
