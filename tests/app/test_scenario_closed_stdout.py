"""A reader that stops reading (``scenario run ... | head``, ``scenario list | head -1``) is
not an error (docs/scenarios.md "Exit codes"): the rest of stdout is dropped quietly, the exit
code is the command's own, and ``--out DIR/events.jsonl`` is complete (it is written before
stdout). Before: a BrokenPipeError traceback, exit 1, and no events.jsonl.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHORT = ('[scenario]\nname = "short"\nduration_s = 0.05\n'
         '[[step]]\nat = 0.0\ncaption = "hello"\n')


def run_with_closed_stdout(*args: str) -> subprocess.CompletedProcess[str]:
    """The pipe's read end is closed before the command starts: its first write fails."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        return subprocess.run([sys.executable, "-m", "app", *args], cwd=ROOT, stdout=write_end,
                              stderr=subprocess.PIPE, text=True, timeout=120, check=False)
    finally:
        os.close(write_end)


def test_scenario_run_into_a_closed_pipe_keeps_events_jsonl(tmp_path: Path) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    out_dir = tmp_path / "out"
    done = run_with_closed_stdout("scenario", "run", str(scenario), "--out", str(out_dir))
    assert done.stderr == ""
    assert done.returncode == 0
    lines = (out_dir / "events.jsonl").read_text(encoding="utf-8").splitlines()
    assert any('"caption"' in line for line in lines)


def test_scenario_list_into_a_closed_pipe() -> None:
    done = run_with_closed_stdout("scenario", "list")
    assert done.stderr == ""
    assert done.returncode == 0


def run_with_fd1_closed(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m app ... >&-``: no fd 1 at all, so Python starts with sys.stdout None."""
    return subprocess.run([sys.executable, "-m", "app", *args], cwd=ROOT,
                          stderr=subprocess.PIPE, text=True, timeout=120, check=False,
                          preexec_fn=lambda: os.close(1))


def test_scenario_run_with_no_stdout_keeps_events_jsonl(tmp_path: Path) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    out_dir = tmp_path / "out"
    done = run_with_fd1_closed("scenario", "run", str(scenario), "--out", str(out_dir))
    assert done.stderr == ""
    assert done.returncode == 0
    lines = (out_dir / "events.jsonl").read_text(encoding="utf-8").splitlines()
    assert any('"caption"' in line for line in lines)


def test_scenario_list_with_no_stdout() -> None:
    done = run_with_fd1_closed("scenario", "list")
    assert done.stderr == ""
    assert done.returncode == 0
