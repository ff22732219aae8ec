"""Interrupting ``scenario run`` (Ctrl-C, a CI job's timeout sending SIGTERM): one line,
exit 128 + the signal, and a folder that says it is incomplete (docs/scenarios.md "Exit
codes", "Output folder"): ``events.jsonl`` is the last file a run writes, atomically, so a
folder without it is a run that did not finish, and a reader never sees half a file.
Before: SIGTERM killed the process silently (exit -15 / 143 from a shell), SIGINT was a
KeyboardInterrupt traceback (exit 1).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from app.cli import main

ROOT = Path(__file__).resolve().parents[2]
SHORT = ('[scenario]\nname = "short"\nduration_s = 0.05\n'
         '[[step]]\nat = 0.0\ncaption = "hello"\n')

# The run is replaced by one that signals its own process, then waits for the signal to act.
SIGNALLING_RUN = textwrap.dedent("""
    import os, signal, sys, time
    import app.cli

    def run_scenario(*args, **kwargs):
        os.kill(os.getpid(), signal.{signal})
        time.sleep(30)
        raise AssertionError("the signal did not stop the run")

    app.cli.run_scenario = run_scenario
    sys.exit(app.cli.main(sys.argv[1:]))
""")


@pytest.mark.parametrize(("name", "code"), [("SIGTERM", 143), ("SIGINT", 130)])
def test_a_signal_mid_run_is_one_line_and_no_events_jsonl(
        tmp_path: Path, name: str, code: int) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    (out_dir / "events.jsonl").write_text("an earlier run's\n", encoding="utf-8")
    done = subprocess.run([sys.executable, "-c", SIGNALLING_RUN.format(signal=name), "scenario",
                           "run", str(scenario), "--out", str(out_dir)],
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == code, done.stderr
    removed, interrupted = done.stderr.splitlines()  # no traceback
    assert removed.startswith(f"fieldrig: removed {out_dir / 'events.jsonl'} ")
    assert interrupted.startswith("fieldrig: interrupted: ")
    assert f"{out_dir} is incomplete" in interrupted
    assert list(out_dir.iterdir()) == []  # the earlier run's file went, no new one came


def test_events_jsonl_comes_whole_by_one_rename_in_the_folder(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    out_dir = tmp_path / "out"
    renames: list[tuple[Path, Path, str]] = []
    real_replace = os.replace

    def spy(src: str, dst: str) -> None:
        renames.append((Path(src), Path(dst), Path(src).read_text(encoding="utf-8")))
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", spy)
    assert main(["scenario", "run", str(scenario), "--out", str(out_dir)]) == 0
    printed = capsys.readouterr().out
    into_events = [r for r in renames if r[1] == out_dir / "events.jsonl"]
    assert into_events, renames
    src, _, content = into_events[-1]
    assert src.parent == out_dir and content == printed
    assert sorted(p.name for p in out_dir.iterdir()) == ["events.jsonl"]  # no temp file left


def test_sigterm_handler_is_put_back_after_a_run(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    before = signal.getsignal(signal.SIGTERM)
    assert main(["scenario", "run", str(scenario), "--quiet"]) == 0
    assert signal.getsignal(signal.SIGTERM) is before
