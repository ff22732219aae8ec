"""Serving with a ``--state-dir`` that cannot be a directory at all (a file, a path under a
file) is bad input: one ``fieldrig: error: --state-dir: ...`` line and exit 2, before any rig
serves, as ``scenario run`` says it. Before: the FlashError of the first flash read,
``[Errno 20] Not a directory``, exit 3. A directory that is there (or can be) but cannot be
written still serves: that is the devices' simulated flash failure (docs/rig-file.md "Where
the flash lives")."""

from __future__ import annotations

from pathlib import Path

import pytest
from served_process import free_ports

from app.cli import EXIT_BAD_INPUT, main


def _serve(state_dir: Path | str, capsys: pytest.CaptureFixture[str],
           *extra: str) -> tuple[int, str, str]:
    port = free_ports(4, 26000)
    code = main(["--state-dir", str(state_dir), "--no-record", "--run-for", "0", "--port",
                 str(port), "--modbus-port", str(port + 2), *extra])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize(("where", "extra"), [
    ("a file", ()),
    ("under a file", ()),
    ("a file", ("--rigs", "2")),  # STATE_DIR/rig1, under the file
], ids=["file", "under-a-file", "file-rigs-2"])
def test_a_state_dir_that_cannot_be_a_directory_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], where: str,
        extra: tuple[str, ...]) -> None:
    plain = tmp_path / "plain"
    plain.write_text("mine", encoding="utf-8")
    state_dir = plain if where == "a file" else plain / "state"
    code, out, err = _serve(state_dir, capsys, *extra)
    assert code == EXIT_BAD_INPUT, err
    assert err.splitlines() == [err.strip()], err  # one line, no traceback
    assert err.startswith(f"fieldrig: error: --state-dir: {state_dir}"), err
    assert "Errno" not in err
    assert "FieldRig:" not in out  # refused before any rig served
    assert plain.read_text(encoding="utf-8") == "mine"


@pytest.mark.parametrize("state_dir", ["/proc", "/proc/fieldrig-state"])
def test_a_state_dir_that_cannot_be_written_still_serves(
        state_dir: str, capsys: pytest.CaptureFixture[str]) -> None:
    """No file can be made in /proc (for root too): the rig serves and a flash write fails
    as the devices' simulated flash failure (SAVE_FLASH, alarm 9), not a refusal."""
    code, out, err = _serve(state_dir, capsys)
    assert code == 0, err
    assert "FieldRig: serving" in out


def test_a_recording_that_cannot_be_written_there_is_bad_input(
        capsys: pytest.CaptureFixture[str]) -> None:
    """Recorded (the default), the session's file goes to STATE_DIR/recordings: a state
    directory no file can be made in cannot take it. Before: ``fieldrig: error:
    /proc/fieldrig-state: No such file or directory``, exit 3, no flag named, nor the way out."""
    port = free_ports(4, 26000)
    code = main(["--state-dir", "/proc/fieldrig-state", "--run-for", "0", "--port", str(port),
                 "--modbus-port", str(port + 2)])
    out, err = capsys.readouterr()
    assert code == EXIT_BAD_INPUT, err
    assert err.splitlines() == [err.strip()], err
    assert err.startswith("fieldrig: error: --state-dir: /proc/fieldrig-state: "), err
    assert "--record PATH" in err and "--no-record" in err, err
    assert "FieldRig:" not in out
