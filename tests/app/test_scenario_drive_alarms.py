"""A drive alarm code the drive's table does not have is refused before the run: the table
is the one of the fieldbus the drive's configuration selects (seed 004 ch. 5 / ch. 6)."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.cli import main
from app.rig_config import build_rig, load_rig_spec
from app.scenario import ScenarioError, check_against, parse_scenario


def alarm(target: str, code: object, action: str = "inject_alarm") -> str:
    shown = f"\"{code}\"" if isinstance(code, str) else code
    return f"[[step]]\nat = 0.5\ntarget = \"{target}\"\naction = \"{action}\"\ncode = {shown}\n"


def test_an_unknown_alarm_code_exits_2_before_the_run(tmp_path, capsys) -> None:
    """code = 99 passed the check and failed at the step (exit 1, events.jsonl written)."""
    path = tmp_path / "s.toml"
    path.write_text("[scenario]\nname = \"t\"\n" + alarm("drive", 99), encoding="utf-8")
    rc = main(["scenario", "run", str(path), "--quiet", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.splitlines()
    assert rc == 2, err
    assert len(err) == 1 and err[0].startswith(f"fieldrig: error: {path}: step[0] (at 0.5 s): "
                                               "no alarm 99 (codes: 1, 2, "), err
    assert not (tmp_path / "o" / "events.jsonl").exists()


@pytest.fixture
def rig(tmp_path: Path):
    path = tmp_path / "rig.toml"
    path.write_text('[rig]\nname = "two drives"\n[[servo]]\nid = "pn"\nfieldbus = "profinet"\n'
                    '[[servo]]\nid = "mb"\nfieldbus = "modbus"\nnode_id = 2\n',
                    encoding="utf-8")
    return build_rig(load_rig_spec(path), state_dir=None)


@pytest.mark.parametrize(("text", "message"), [
    (alarm("pn", 35), r"no alarm 35 \(codes: .*, 34\)"),  # ch. 6 stops at 34
    (alarm("mb", "PROFINET_INIT_1"), "no alarm named 'PROFINET_INIT_1'"),
    (alarm("mb", "NO_SUCH", "clear_alarm"), "no alarm named 'NO_SUCH'"),
])
def test_the_table_is_the_drives_own_fieldbus(rig, text: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=r"step\[0\] \(at 0.5 s\): " + message):
        check_against(parse_scenario(text, "s.toml"), rig)


def test_codes_of_the_drives_table_pass(rig) -> None:
    check_against(parse_scenario(alarm("pn", "PROFINET_INIT_1") + alarm("mb", 35)
                                 + alarm("mb", "16"), "s.toml"), rig)


def test_a_refused_alarm_reset_is_the_drives_reaction_not_a_failed_step(tmp_path,
                                                                         capsys) -> None:
    """Seed 004 ch. 5 / ch. 6 "Reset allarmi": a reset that does not succeed means the alarm
    condition persists; the drive answers no error, it stays in Fault. The step passes (exit
    0) and the run says so in the drive's log line; expect_error does not fit it."""
    head = "[scenario]\nname = \"t\"\nduration_s = 2\n" + alarm("drive", 16)
    reset = "[[step]]\nat = 1.0\ntarget = \"drive\"\naction = \"alarm_reset\"\n"
    path = tmp_path / "s.toml"
    path.write_text(head + reset, encoding="utf-8")
    assert main(["scenario", "run", str(path), "--quiet", "--out", str(tmp_path / "o")]) == 0
    events = (tmp_path / "o" / "events.jsonl").read_text(encoding="utf-8")
    assert '"text": "alarm reset refused: alarm 16 persists' in events, events
    path.write_text(head + reset + "expect_error = true\n", encoding="utf-8")
    assert main(["scenario", "run", str(path), "--quiet"]) == 1
    assert "expected an error, the command was accepted" in capsys.readouterr().err
