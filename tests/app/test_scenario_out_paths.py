"""``scenario run --out/--record`` with a path that cannot take the output (docs/scenarios.md).

A bad output path is the same class of mistake as a wrong scenario file: one ``fieldrig:
error:`` line, exit 2, checked before the run, nothing written. An ``--out`` that holds a
previous run's files gets this run's only (the old ``NN-*.png`` and ``events.jsonl`` go; other
files stay).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from app.cli import main

SHORT = ('[scenario]\nname = "short"\nduration_s = 0.05\n'
         '[[step]]\nat = 0.0\ncaption = "hello"\n')


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "short.toml"
    path.write_text(SHORT, encoding="utf-8")
    return path


def one_error_line(err: str) -> str:
    assert err.splitlines() == [err.strip()], err  # one line, no traceback
    assert err.startswith("fieldrig: error: "), err
    return err


def test_out_naming_a_file_is_refused_before_the_run(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    taken = tmp_path / "taken"
    taken.write_text("mine", encoding="utf-8")
    record = tmp_path / "run.rrd"
    code = main(["scenario", "run", str(scenario), "--out", str(taken), "--record",
                 str(record), "--quiet"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert "--out" in one_error_line(err)
    assert taken.read_text(encoding="utf-8") == "mine"
    assert not record.exists()  # the run did not happen: no recording that looks complete


def test_record_naming_a_directory_is_refused_before_the_run(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "recordings"
    folder.mkdir()
    out_dir = tmp_path / "out"
    code = main(["scenario", "run", str(scenario), "--out", str(out_dir), "--record",
                 str(folder)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""  # no event lines: the run did not happen
    assert "--record" in one_error_line(err)
    assert list(folder.iterdir()) == []
    assert not (out_dir / "events.jsonl").exists()


def test_record_under_a_file_is_refused(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "plain").write_text("", encoding="utf-8")
    code = main(["scenario", "run", str(scenario), "--record", str(tmp_path / "plain" / "x.rrd"),
                 "--quiet"])
    assert code == 2
    assert "--record" in one_error_line(capsys.readouterr().err)


def test_served_record_naming_a_directory_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["--record", str(tmp_path), "--run-for", "0", "--port", "18931",
                 "--modbus-port", "18932", "--state-dir", str(tmp_path / "var")])
    out, err = capsys.readouterr()
    assert code == 2
    assert "--record" in one_error_line(err)
    assert "serving" not in out


def test_a_previous_run_s_files_are_replaced_and_others_kept(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    old = ["01-op.png", "02-in_alarm.png", "12-x.y.png"]
    for name in old:
        (out_dir / name).write_bytes(b"old picture")
    (out_dir / "events.jsonl").write_text("old\n", encoding="utf-8")
    kept = ["notes.txt", "op.png", "1-op.png", "01-op.png.bak", "events.jsonl.old"]
    for name in kept:
        (out_dir / name).write_text("keep", encoding="utf-8")
    (out_dir / "03-sub.png").mkdir()  # not a file FieldRig wrote
    assert main(["scenario", "run", str(scenario), "--out", str(out_dir), "--quiet"]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(
        [*kept, "03-sub.png", "events.jsonl"])
    assert '"caption"' in (out_dir / "events.jsonl").read_text(encoding="utf-8")


@pytest.mark.parametrize(("flag", "path"), [("--record", "/proc/fieldrig-check.rrd"),
                                            ("--out", "/proc/fieldrig-out"),
                                            ("--out", "/proc")])
def test_a_place_no_file_can_be_made_is_refused_for_root_too(
        scenario: Path, capsys: pytest.CaptureFixture[str], flag: str, path: str) -> None:
    """access() says yes to root for /proc, where no file can be made: the recorder's file
    sink then failed after the run had started (a RuntimeError traceback, exit 1), and so did
    events.jsonl in an existing --out there. A trial file is the check that holds for every
    user (CI runs as root)."""
    code = main(["scenario", "run", str(scenario), flag, path, "--quiet"])
    err = one_error_line(capsys.readouterr().err)
    assert code == 2 and flag in err and "/proc" in err


@pytest.mark.parametrize("where", ["a file", "/proc/fieldrig-state", "/proc"])
def test_a_state_dir_that_cannot_keep_flash_is_refused_before_the_run(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], where: str) -> None:
    """A file was a FlashError traceback; a folder no file can be made in (for root too:
    /proc) ran to exit 0 with another result than asked for, a SAVE_FLASH alarm in it, as
    the flash write the run needed failed. A served rig keeps that simulated flash failure
    (docs/rig-file.md "Where the flash lives"); a scenario run is refused."""
    state_dir = tmp_path / "plain" if where == "a file" else Path(where)
    if where == "a file":
        state_dir.write_text("mine", encoding="utf-8")
    code = main(["scenario", "run", str(scenario), "--state-dir", str(state_dir), "--quiet"])
    err = one_error_line(capsys.readouterr().err)
    assert code == 2 and "--state-dir" in err and str(state_dir) in err
    if where == "a file":
        assert state_dir.read_text(encoding="utf-8") == "mine"


def test_a_state_dir_to_be_made_is_fine(scenario: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    state_dir = tmp_path / "new" / "state"
    assert main(["scenario", "run", str(scenario), "--state-dir", str(state_dir),
                 "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_each_removed_file_is_said_on_stderr_not_stdout(
        scenario: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A user's own ``01-op.png`` in --out goes like an earlier run's: each removal is one
    line on stderr (stdout is the event lines a pipeline parses)."""
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    for name in ("01-op.png", "events.jsonl"):
        (out_dir / name).write_text("mine", encoding="utf-8")
    (out_dir / "notes.txt").write_text("keep", encoding="utf-8")
    assert main(["scenario", "run", str(scenario), "--out", str(out_dir)]) == 0
    out, err = capsys.readouterr()
    why = "(--out holds this run's files only)"
    assert err.splitlines() == [f"fieldrig: removed {out_dir / '01-op.png'} {why}",
                                f"fieldrig: removed {out_dir / 'events.jsonl'} {why}"]
    assert "removed" not in out


def test_out_help_says_it_removes_files(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["scenario", "run", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "removes" in help_text and "events.jsonl" in help_text and "NN-name.png" in help_text


@pytest.mark.parametrize("umask", [0o022, 0o077])
def test_events_jsonl_has_the_mode_of_the_run_s_other_files(
        scenario: Path, tmp_path: Path, umask: int) -> None:
    """A CI job hands --out to another user (an artifact store, a web server): events.jsonl
    was 0600 (its temporary file's mode, renamed over) beside 0644 pictures under umask 022.
    It is made as open() makes a file: 0666 less the umask."""
    out = tmp_path / "out"
    old = os.umask(umask)
    try:
        assert main(["scenario", "run", str(scenario), "--out", str(out), "--quiet"]) == 0
    finally:
        os.umask(old)
    assert stat.S_IMODE((out / "events.jsonl").stat().st_mode) == 0o666 & ~umask
