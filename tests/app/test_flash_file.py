"""The flash file: old or new content, never a broken file (issue 2 §3 CNF, issue 7 persistence)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from app.flash_file import CorruptFlash, FileFlash
from devices.flash import FlashError


def test_missing_file_loads_none(tmp_path: Path) -> None:
    assert FileFlash(tmp_path / "none.flash").load() is None


def test_round_trip_and_replace(tmp_path: Path) -> None:
    flash = FileFlash(tmp_path / "sub" / "dev.flash")
    flash.save(b"first")
    flash.save(b"second")
    assert FileFlash(flash.path).load() == b"second"
    assert sorted(p.name for p in flash.path.parent.iterdir()) == ["dev.flash"]


@pytest.mark.parametrize("damage", [
    lambda b: b[:5],                      # truncated inside the header
    lambda b: b[:-1],                     # truncated payload
    lambda b: b[:-1] + bytes([b[-1] ^ 1]),  # flipped bit
    lambda b: b"XXXX" + b[4:],            # foreign file
])
def test_damaged_file_is_reported_not_used(tmp_path: Path, damage) -> None:
    flash = FileFlash(tmp_path / "dev.flash")
    flash.save(b'["DB16", "AI8D"]')
    flash.path.write_bytes(damage(flash.path.read_bytes()))
    with pytest.raises(CorruptFlash):
        flash.load()


def test_unwritable_location_raises_flash_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(FlashError):
        FileFlash(blocker / "dev.flash").save(b"x")


_WRITER = textwrap.dedent("""
    import sys
    from app.flash_file import FileFlash
    flash = FileFlash(sys.argv[1])
    i = 0
    print("ready", flush=True)
    while True:
        i += 1
        flash.save((b"%08d" % i) * 20000)
""")


@pytest.mark.parametrize("delay", [0.05, 0.13, 0.31])
def test_killed_writer_leaves_old_or_new(tmp_path: Path, delay: float) -> None:
    """SIGKILL a process in the middle of a stream of saves: the file is always complete."""
    path = tmp_path / "dev.flash"
    FileFlash(path).save(b"%08d" % 0 * 20000)
    proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(path)], stdout=subprocess.PIPE,
                            cwd=Path(__file__).resolve().parents[2])
    assert proc.stdout is not None and proc.stdout.readline().strip() == b"ready"
    time.sleep(delay)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    data = FileFlash(path).load()
    assert data is not None and len(data) == 8 * 20000
    assert data == data[:8] * 20000  # one whole generation, not a mix
    FileFlash(path).save(b"next")  # the next save clears what the killed writer left
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dev.flash"]
