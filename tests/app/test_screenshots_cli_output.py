"""``scenario run --screenshots``: what it prints besides the events (docs/scenarios.md).

A wrong file is refused before the dashboard's server starts (one ``fieldrig: error:`` line,
not viser's banner and "Server stopped" first), and ``--quiet`` keeps viser's banner out of
the output. No browser needed: the refusal comes before one, and the banner is the server's.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import ServedRig

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("quiet", [False, True])
def test_a_wrong_file_is_refused_before_the_server_starts(tmp_path: Path, quiet: bool) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[scenario]\nname = "x"\n[[step]]\nat = 0.0\ntarget = "fastcat"\n'
                   'action = "inject_fault"\nfault = "NOT_A_FAULT"\n', encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "app", "scenario", "run", str(bad), "--out",
                           str(tmp_path / "out"), "--screenshots", *(["--quiet"] * quiet)],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.splitlines() == [done.stderr.strip()], done.stderr  # one line
    assert done.stderr.startswith("fieldrig: error: ") and "NOT_A_FAULT" in done.stderr


def test_quiet_keeps_viser_s_banner_out(capfd: pytest.CaptureFixture[str]) -> None:
    served = ServedRig.start(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None), quiet=True)
    served.stop()
    out, err = capfd.readouterr()
    assert "viser" not in out + err, out + err


def test_without_quiet_the_banner_goes_to_stderr(capfd: pytest.CaptureFixture[str]) -> None:
    """stdout carries the event lines only; the banner (where the dashboard is) on stderr."""
    served = ServedRig.start(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    served.stop()
    out, err = capfd.readouterr()
    assert "viser" not in out and "viser" in err
