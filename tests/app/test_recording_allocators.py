"""The recorder gives what its sends freed back to the OS (issue 7, "Soak: memory grows less
than 10 MB"; app/recording/allocators.py, docs/recording.md "Memory given back").

A periodic flush sends minutes of rows at once; rerun's mimalloc, pyarrow's mimalloc pool and
glibc each kept that peak (the soak's RSS rose ~3 MB at its first 300 s flush). Checked here:
rerun's mimalloc is set up before rerun loads, pyarrow's process-wide pool only by a recorder
(a user's choices kept, a rig served without a recording touching neither), and glibc is
trimmed once per flush period, not per sample or per chunk.
"""

from __future__ import annotations

import os
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


def _fresh(code: str, **env_set: str) -> list[str]:
    """``code``'s printed words, run in a fresh interpreter without MIMALLOC_ / ARROW_ pool
    settings but ``env_set``."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("MIMALLOC_") and k != "ARROW_DEFAULT_MEMORY_POOL"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**env, **env_set}, cwd=Path(__file__).resolve().parents[2],
                         timeout=120, check=True)
    return out.stdout.split()


def test_importing_the_recorder_sets_mimalloc_up_before_rerun_loads() -> None:
    code = ("import os, sys\n"
            "import app.recording\n"
            "assert 'rerun_bindings' in sys.modules\n"
            "print(os.environ.get('MIMALLOC_PURGE_DELAY'))")
    assert _fresh(code) == ["0"]


def test_pyarrows_pool_is_switched_by_a_recorder_not_by_an_import(tmp_path: Path) -> None:
    """pyarrow's default pool is process-wide: a library user's own Arrow work uses it too, so
    importing the package (a type hint, a served rig without a recording) leaves it alone."""
    code = ("import pyarrow as pa\n"
            "before = pa.default_memory_pool().backend_name\n"
            "from app.recording import RigRecorder\n"
            "imported = pa.default_memory_pool().backend_name\n"
            f"RigRecorder({str(tmp_path / 'a.rrd')!r}, blueprint=False).close()\n"
            "print(before == imported, pa.default_memory_pool().backend_name)")
    assert _fresh(code) == ["True", "system"]


def test_a_users_arrow_pool_setting_is_kept(tmp_path: Path) -> None:
    code = ("import pyarrow as pa\n"
            "from app.recording import RigRecorder\n"
            f"RigRecorder({str(tmp_path / 'a.rrd')!r}, blueprint=False).close()\n"
            "print(pa.default_memory_pool().backend_name)")
    assert _fresh(code, ARROW_DEFAULT_MEMORY_POOL="jemalloc") == ["jemalloc"]


def test_a_served_rig_without_a_recording_loads_no_rerun() -> None:
    """Serving without ``--record`` (``--no-record``, the tests' rigs) sets no allocator up:
    rerun is not even loaded."""
    code = ("import os, sys\n"
            "import app.ui.panels.classroom_rig\n"
            "import app.ui.panels.classroom\n"
            "print('rerun' in sys.modules, os.environ.get('MIMALLOC_PURGE_DELAY'))")
    assert _fresh(code) == ["False", "None"]


def test_a_users_mimalloc_setting_is_kept() -> None:
    code = ("import os\nimport app.recording\nprint(os.environ['MIMALLOC_PURGE_DELAY'])")
    assert _fresh(code, MIMALLOC_PURGE_DELAY="25") == ["25"]


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
