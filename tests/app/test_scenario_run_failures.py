"""``scenario run`` failures that are not bad input (docs/scenarios.md "Exit codes").

The machine failing the run (a file system error, the browser dying) is one ``fieldrig:
error:`` line and exit 3, not a traceback and exit 1 (which says "a step failed"). An output
name the run will need that is taken by something else (a directory called ``events.jsonl`` or
``01-up.png``) is caught before the run, as a bad ``--out`` is: exit 2.
"""

from __future__ import annotations

import errno
import shutil
from pathlib import Path
from typing import Any

import pytest

import app.cli
import app.out_paths
import app.screenshots
from app.cli import main

SHORT = ('[scenario]\nname = "short"\nduration_s = 0.05\n'
         '[[step]]\nat = 0.0\ncaption = "hello"\n'
         '[[step]]\nat = 0.01\ncheckpoint = "up"\n')


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "short.toml"
    path.write_text(SHORT, encoding="utf-8")
    return path


def one_error_line(err: str) -> str:
    assert err.splitlines() == [err.strip()], err  # one line, no traceback
    assert err.startswith("fieldrig: error: "), err
    return err


def test_a_directory_named_events_jsonl_is_refused_before_the_run(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """It was an IsADirectoryError traceback after the whole run."""
    out_dir = tmp_path / "out"
    (out_dir / "events.jsonl").mkdir(parents=True)
    code = main(["scenario", "run", str(scenario), "--out", str(out_dir)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert "events.jsonl" in one_error_line(err) and "--out" in err
    assert (out_dir / "events.jsonl").is_dir()


def test_a_directory_named_like_a_screenshot_is_refused_before_the_run(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``01-up.png`` is the picture of checkpoint "up": a directory there was an
    IsADirectoryError traceback from inside Playwright, mid-run. No browser is needed: the
    refusal comes first."""
    out_dir = tmp_path / "out"
    (out_dir / "01-up.png").mkdir(parents=True)
    code = main(["scenario", "run", str(scenario), "--out", str(out_dir), "--screenshots",
                 "--quiet"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert "01-up.png" in one_error_line(err)


def test_an_old_events_jsonl_that_cannot_be_removed_is_one_line(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """(root removes files anywhere it may write: the refusal is simulated.)"""
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    (out_dir / "events.jsonl").write_text("old\n", encoding="utf-8")
    real_unlink = Path.unlink

    def refuse(self: Path, missing_ok: bool = False) -> None:
        if self.name == "events.jsonl":
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        real_unlink(self, missing_ok=missing_ok)

    monkeypatch.setattr(Path, "unlink", refuse)
    code = main(["scenario", "run", str(scenario), "--out", str(out_dir), "--quiet"])
    err = one_error_line(capsys.readouterr().err)
    assert code == 2 and "Permission denied" in err and "events.jsonl" in err


def test_a_file_system_error_during_the_run_is_exit_3(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The --out folder replaced by a file while the run goes: nothing the user typed was
    wrong, and no step failed."""
    out_dir = tmp_path / "out"
    real_run = app.cli.run_scenario

    def run_then_break_out(*args: Any, **kwargs: Any) -> Any:
        result = real_run(*args, **kwargs)
        shutil.rmtree(out_dir)
        out_dir.write_text("not a folder any more", encoding="utf-8")
        return result

    monkeypatch.setattr(app.cli, "run_scenario", run_then_break_out)
    code = main(["scenario", "run", str(scenario), "--out", str(out_dir), "--quiet"])
    err = one_error_line(capsys.readouterr().err)
    assert code == 3 and str(out_dir) in err


class DyingChromium:
    """Chromium that dies once the page is asked for: Playwright's TargetClosedError."""

    def __init__(self, executable: str) -> None:
        pass

    def open(self, served: Any, show_player: bool = False) -> Any:
        from playwright._impl._errors import TargetClosedError

        raise TargetClosedError("Locator.count: Target page, context or browser has been "
                                "closed\nBrowser logs: ...")

    def __enter__(self) -> DyingChromium:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


@pytest.mark.skipif(not Path(app.screenshots.CHROMIUM).exists(), reason="no chromium")
def test_chromium_dying_mid_run_is_one_line_and_exit_3(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(app.screenshots, "Chromium", DyingChromium)
    code = main(["scenario", "run", str(scenario), "--out", str(tmp_path / "out"),
                 "--screenshots", "--quiet"])
    out, err = capsys.readouterr()
    assert code == 3 and out == ""
    assert "browser" in one_error_line(err) and "closed" in err
