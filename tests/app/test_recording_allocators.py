"""The recorder gives what its sends freed back to the OS (issue 7, "Soak: memory grows less
than 10 MB"; app/recording/allocators.py, docs/recording.md "Memory given back").

A periodic flush sends minutes of rows at once; rerun's mimalloc, pyarrow's mimalloc pool and
glibc each kept that peak (the soak's RSS rose ~3 MB at its first 300 s flush). Checked here:
the allocators are set up before rerun loads, and glibc is trimmed once per flush period, not
per sample or per chunk.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from app.recording import RigRecorder, allocators, recorder

SAMPLE_US = 10_000
PERIOD_US = 1_000_000


def moving(i: int) -> dict[str, Any]:
    return {"rig": "soak", "devices": {"axis": {
        "kind": "servo", "position": float(i), "velocity": float(i % 5),
        "following_error": i / 7, "ds402_state": "OPERATION_ENABLED"}}}


def test_importing_the_recorder_sets_the_allocators_up_before_rerun_loads() -> None:
    code = ("import os, sys\n"
            "import app.recording\n"
            "import pyarrow as pa\n"
            "assert 'rerun_bindings' in sys.modules\n"
            "print(os.environ.get('MIMALLOC_PURGE_DELAY'), pa.default_memory_pool().backend_name)")
    env = {k: v for k, v in __import__("os").environ.items() if not k.startswith("MIMALLOC_")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=Path(__file__).resolve().parents[2], timeout=120, check=True)
    assert out.stdout.split() == ["0", "system"]


def test_a_users_mimalloc_setting_is_kept() -> None:
    code = ("import os\nimport app.recording\nprint(os.environ['MIMALLOC_PURGE_DELAY'])")
    env = dict(__import__("os").environ, MIMALLOC_PURGE_DELAY="25")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=Path(__file__).resolve().parents[2], timeout=120, check=True)
    assert out.stdout.strip() == "25"


def test_glibc_is_trimmed_once_per_flush_period(tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[int] = []
    monkeypatch.setattr(recorder.allocators, "release_freed", lambda: bool(calls.append(1)))
    rec = RigRecorder(tmp_path / "t.rrd", blueprint=False, flush_period_us=PERIOD_US)
    try:
        periods = 5
        for i in range(periods * PERIOD_US // SAMPLE_US + 1):
            rec.observe(i * SAMPLE_US, moving(i), [])
    finally:
        rec.close()
    assert len(calls) == periods


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc_trim")
def test_release_freed_calls_malloc_trim_where_there_is_one(
        monkeypatch: pytest.MonkeyPatch) -> None:
    assert allocators.release_freed()  # this machine's glibc
    monkeypatch.setattr(allocators, "_TRIM", None)  # musl, macOS, Windows
    assert not allocators.release_freed()


def test_glibc_is_trimmed_after_a_full_chunk_is_sent(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[int] = []
    monkeypatch.setattr(recorder.allocators, "release_freed", lambda: bool(calls.append(1)))
    rec = RigRecorder(tmp_path / "c.rrd", blueprint=False, flush_period_us=3600 * 10**6,
                      chunk_rows=100)
    try:
        for i in range(99):  # the moving signals hold under a chunk: nothing sent yet
            rec.observe(i * SAMPLE_US, moving(i), [])
        assert calls == []
        rec.observe(99 * SAMPLE_US, moving(99), [])  # a chunk's worth: sent, then trimmed
        assert len(calls) == 1
    finally:
        rec.close()
