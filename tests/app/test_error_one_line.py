"""A refused rig file or scenario is one error line even when a key holds a line break.

TOML lets a quoted key hold any character (``"a\\u0085b" = 0``); the messages name the key, so a
newline, NEL (U+0085), a line or paragraph separator or another control character in it split
the ``fieldrig: error:`` line (docs/hardening.md "Rig files and scenarios": one line). Found by
``tests/hardening/test_fuzz_config.py --full`` (a key ``"\\x85"`` in [scenario]).
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Callable
from pathlib import Path

import pytest

from app.cli import main
from app.rig_config import RigConfigError, parse_rig_spec
from app.scenario import ScenarioError, parse_scenario

BREAKS = ("\\n", "\\r", "\\u0085", "\\u2028", "\\u2029", "\\u000b", "\\u001c", "\\u001b")


@pytest.mark.parametrize("escape", BREAKS)
@pytest.mark.parametrize(("error", "text", "parse", "prefix"), [
    (ScenarioError, '[scenario]\n"a{}b" = 0\n', parse_scenario, "f.toml: scenario.a\\"),
    (RigConfigError, '"a{}b" = 1\n', parse_rig_spec, "f.toml: a\\"),
], ids=["scenario", "rig"])
def test_a_key_with_a_line_break_is_named_on_one_line(
        escape: str, error: type[Exception], text: str, parse: Callable[[str, str], object],
        prefix: str) -> None:
    with pytest.raises(error) as caught:
        parse(text.format(escape), "f.toml")
    message = str(caught.value)
    assert len(message.splitlines()) == 1 and message.isprintable(), repr(message)
    assert message.startswith(prefix) and "b: unknown key" in message


def test_the_cli_prints_one_line(tmp_path: Path) -> None:
    path = tmp_path / "fuzz.toml"
    path.write_text('[scenario]\n"\\u0085" = 0\n', encoding="utf-8")
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(["scenario", "run", str(path), "--quiet"])
    lines = err.getvalue().splitlines()
    assert code == 2 and len(lines) == 1, err.getvalue()
    assert lines[0].startswith("fieldrig: error: ") and "scenario.\\x85: unknown key" in lines[0]
