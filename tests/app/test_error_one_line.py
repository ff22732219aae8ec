"""A refused rig file or scenario is one error line even when a key holds a line break.

TOML lets a quoted key hold any character (``"a\\u0085b" = 0``); the messages name the key, so a
newline, NEL (U+0085), a line or paragraph separator or another control character in it split
the ``fieldrig: error:`` line (docs/hardening.md "Rig files and scenarios": one line). Found by
``tests/hardening/test_fuzz_config.py --full`` (a key ``"\\x85"`` in [scenario]).
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

from app.cli import main
from app.rig_config import RigConfigError, parse_rig_spec
from app.scenario import ScenarioError, parse_scenario

BREAKS = ("\\n", "\\r", "\\u0085", "\\u2028", "\\u2029", "\\u000b", "\\u001c", "\\u001b")


@pytest.mark.parametrize("escape", BREAKS)
def test_a_scenario_key_with_a_line_break_is_named_on_one_line(escape: str) -> None:
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(f'[scenario]\n"a{escape}b" = 0\n', "f.toml")
    message = str(caught.value)
    assert len(message.splitlines()) == 1 and message.isprintable(), repr(message)
    assert message.startswith("f.toml: scenario.a\\") and "b: unknown key" in message


@pytest.mark.parametrize("escape", BREAKS)
def test_a_rig_key_with_a_line_break_is_named_on_one_line(escape: str) -> None:
    with pytest.raises(RigConfigError) as caught:
        parse_rig_spec(f'"a{escape}b" = 1\n', "f.toml")
    message = str(caught.value)
    assert len(message.splitlines()) == 1 and message.isprintable(), repr(message)
    assert message.startswith("f.toml: a\\") and "b: unknown key" in message


def test_the_cli_prints_one_line(tmp_path: Path) -> None:
    path = tmp_path / "fuzz.toml"
    path.write_text('[scenario]\n"\\u0085" = 0\n', encoding="utf-8")
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(["scenario", "run", str(path), "--quiet"])
    lines = err.getvalue().splitlines()
    assert code == 2 and len(lines) == 1, err.getvalue()
    assert lines[0].startswith("fieldrig: error: ") and "scenario.\\x85: unknown key" in lines[0]
