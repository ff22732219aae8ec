"""``python -m app scenario list``: the example scenarios, one per line, sorted by file, each
with its name and the rig file it runs on (tab-separated, paths as a command here takes them)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from app.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "static" / "scenarios").glob("*.toml"))


def test_scenario_list_prints_every_example_with_its_name_and_rig(capsys, monkeypatch) -> None:
    monkeypatch.chdir(ROOT)
    assert main(["scenario", "list"]) == 0
    out = capsys.readouterr()
    rows = [line.split("\t") for line in out.out.splitlines()]
    assert [r[0] for r in rows] == [f"static/scenarios/{p.name}" for p in SCENARIOS]
    assert all(len(r) == 3 for r in rows), rows
    by_file = {Path(r[0]).stem: r for r in rows}
    assert by_file["module_lost_in_op"][1:] == ["Module 2 stops answering in OP",
                                                "static/rigs/default.toml"]
    # The EtherCAT line's scenarios run on the default rig, which is that line.
    assert by_file["cable_pulled"][2] == "static/rigs/default.toml"
    assert by_file["too_many_analog"][2] == "static/rigs/nine_analog.toml"
    assert out.err == ""


def test_scenario_list_from_the_command_line() -> None:
    """The listed paths run as they are printed (from the checkout)."""
    proc = subprocess.run([sys.executable, "-m", "app", "scenario", "list"], cwd=ROOT,
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    first = proc.stdout.splitlines()[0].split("\t")
    assert (ROOT / first[0]).is_file() and (ROOT / first[2]).is_file()
