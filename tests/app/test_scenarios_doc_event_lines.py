"""docs/scenarios.md "Event lines" shows lines of ``module_lost_in_op.toml``: each one is a
line that scenario prints, byte for byte (times included), so a reader can find them in a run."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.cli import main

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "scenarios.md"


def doc_event_lines() -> list[str]:
    section = DOC.read_text(encoding="utf-8").split("## Event lines", 1)[1]
    found = re.search(r"^```json\n(.*?)^```", section, re.M | re.S)
    assert found, "no JSON block under 'Event lines'"
    return found.group(1).splitlines()


def test_the_doc_event_lines_are_lines_of_module_lost_in_op(
        capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    rc = main(["scenario", "run", str(ROOT / "static" / "scenarios" / "module_lost_in_op.toml"),
               "--out", str(tmp_path / "out")])
    printed = capsys.readouterr().out.splitlines()
    assert rc == 0
    lines = doc_event_lines()
    assert lines
    assert [line for line in lines if line not in printed] == []
