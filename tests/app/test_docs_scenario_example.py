"""The scenario file docs/scenarios.md shows as its format runs as written: passes the checks
made before the run (a focus names a module the device holds at that step, ...) and passes.

Its ``rig`` is relative to the scenario's folder (static/scenarios); the copy in tmp_path gets
that rig's absolute path, nothing else changes."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.cli import main

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "scenarios.md"
RIG_LINE = 'rig = "../rigs/default.toml"'


def doc_scenario() -> str:
    blocks = re.findall(r"^```toml\n(.*?)^```", DOC.read_text(encoding="utf-8"), re.M | re.S)
    found = [b for b in blocks if b.startswith("[scenario]")]
    assert len(found) == 1, "one [scenario] example in docs/scenarios.md"
    return found[0]


def test_the_doc_scenario_runs_and_passes(capsys: pytest.CaptureFixture[str],
                                          tmp_path: Path) -> None:
    text = doc_scenario()
    assert RIG_LINE in text
    path = tmp_path / "from_the_doc.toml"
    path.write_text(text.replace(RIG_LINE, f'rig = "{ROOT / "static" / "rigs" / "default.toml"}"'))
    rc = main(["scenario", "run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 0, err
