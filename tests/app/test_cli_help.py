"""What a pipeline reads of the CLI's help and errors: every subcommand and flag is in the help
and the README, every error line starts the same, and the help lists the exit codes."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.cli import EXIT_BAD_INPUT, EXIT_SCENARIO_FAILED, _serve_parser, main

ROOT = Path(__file__).resolve().parents[2]


def help_of(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as info:
        main([*argv, "--help"])
    assert info.value.code == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps where it likes


def error_of(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == EXIT_BAD_INPUT
    return capsys.readouterr().err


def test_the_top_help_names_every_subcommand(capsys) -> None:
    text = help_of([], capsys)
    for command in ("scenario run", "scenario list", "ethercat export-esi"):
        assert command in text


def every_help(capsys: pytest.CaptureFixture[str]) -> dict[str, str]:
    """The help of every command and subcommand: the entry points main dispatches on, then
    each subcommand their help's usage line names (``{list,run}``), and so on down."""
    found: dict[str, str] = {}
    todo: list[list[str]] = [[], ["scenario"], ["ethercat"]]
    while todo:
        argv = todo.pop()
        text = help_of(argv, capsys)
        found[" ".join(argv)] = text
        verbs = re.search(r"\{([\w,-]+)\} \.\.\.", text.split(" options:")[0])
        todo += [[*argv, verb] for verb in verbs[1].split(",")] if verbs else []
    return found


def test_every_help_lists_the_exit_codes(capsys) -> None:
    """README: the exit codes are "at the end of every --help"; scenario list, ethercat and
    ethercat export-esi lacked them."""
    helps = every_help(capsys)
    assert {"", "scenario", "scenario run", "scenario list", "ethercat",
            "ethercat export-esi"} <= set(helps)
    for argv, text in helps.items():
        assert "exit codes: 0 ok" in text, argv
        assert f"{EXIT_SCENARIO_FAILED} a scenario step failed" in text, argv
        assert f"{EXIT_BAD_INPUT} bad input" in text, argv
        assert text.endswith("no traceback"), argv  # at the end


@pytest.mark.parametrize("argv", [
    ["--port", "eighty"],
    ["--no-such-flag"],
    ["scenario"],
    ["scenario", "run"],
    ["scenario", "run", "x.toml", "--bogus"],
    ["ethercat"],
], ids=" ".join)
def test_argparse_errors_start_as_ours(argv: list[str], capsys) -> None:
    """A pipeline greps one prefix: argparse's own errors said ``python -m app: error:``."""
    err = error_of(argv, capsys)
    assert "\nfieldrig: error: " in "\n" + err
    assert "python -m app: error" not in err and "scenario: error" not in err


@pytest.mark.parametrize(("argv", "usage"), [
    (["scenario", "run", "x.toml", "--bogus"], "usage: python -m app scenario run "),
    (["scenario", "list", "--bogus"], "usage: python -m app scenario list "),
    (["ethercat", "export-esi", "--bogus"], "usage: python -m app ethercat export-esi "),
    (["--bogus"], "usage: python -m app "),
], ids=lambda v: " ".join(v) if isinstance(v, list) else "")
def test_an_unknown_flag_shows_the_usage_it_was_given_to(argv: list[str], usage: str,
                                                          capsys) -> None:
    """argparse leaves a subcommand's unknown flags to the top parser, which printed its own
    usage: ``scenario run FILE --bogus`` showed ``python -m app scenario [-h] {list,run} ...``,
    which names none of run's flags."""
    err = error_of(argv, capsys)
    lines = err.splitlines()  # the usage (wrapped where argparse likes), then the error
    assert lines[0].startswith(usage), err
    assert not lines[0].startswith(usage + "[-h] {"), err  # not its parent's
    assert lines[-1] == "fieldrig: error: unrecognized arguments: --bogus", err


def test_every_serve_flag_is_in_the_readme() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    flags = [option for action in _serve_parser()._actions for option in action.option_strings
             if option.startswith("--") and option != "--help"]
    assert "--run-for" in flags
    assert [f for f in flags if f"`{f}" not in readme] == []


SPEED_AND_TIME = [
    (["--speed", "nan"], "--speed: 'nan' is not a speed: give a number in (0, 1000]"),
    (["--speed", "0"], "--speed: '0' is not a speed: give a number in (0, 1000]"),
    (["--speed", "-2"], "--speed: '-2' is not a speed"),
    (["--speed", "inf"], "--speed: 'inf' is not a speed"),
    (["--speed", "fast"], "--speed: 'fast' is not a speed"),
    (["--run-for", "nan"], "--run-for: 'nan' is not a time: give seconds >= 0"),
    (["--run-for", "-1"], "--run-for: '-1' is not a time"),
]


@pytest.mark.parametrize(("argv", "why"), SPEED_AND_TIME,
                         ids=[" ".join(argv) for argv, _ in SPEED_AND_TIME])
def test_a_speed_or_time_that_cannot_be_served_is_refused(argv: list[str], why: str,
                                                          capsys) -> None:
    """``--speed nan`` served and its simulation thread died in a traceback (exit 0); a
    speed <= 0 or a negative ``--run-for`` served a rig that never moved or stopped at once,
    with exit 0: a smoke test passed on nothing. The runtime's own range is (0, 1000]."""
    err = error_of([*argv, "--port", "0"], capsys)  # the old code stops there, serving nothing
    assert f"fieldrig: error: argument {why}" in err, err
    assert "Traceback" not in err


@pytest.mark.parametrize("argv", [
    ["--record", "x.rrd", "--no-record"],
    ["--no-record", "--record", "x.rrd"],
], ids=" ".join)
def test_record_and_no_record_together_are_refused(argv: list[str], tmp_path: Path,
                                                   capsys) -> None:
    """``--record X --no-record`` served without recording and never said that X was
    dropped: two contradicting options are one error line, exit 2, nothing served."""
    err = error_of([*argv, "--port", "0", "--state-dir", str(tmp_path)], capsys)
    last = err.splitlines()[-1]
    assert last.startswith("fieldrig: error: argument "), err
    assert "--record" in last and "--no-record" in last and "not allowed with" in last, err
