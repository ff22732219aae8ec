"""Scenario files: format and errors (issue 2 §4)."""

from __future__ import annotations

import tomllib

import pytest

from app.scenario import ScenarioError, parse_scenario


def test_steps_at_and_after_are_in_time_order() -> None:
    sc = parse_scenario("""
[scenario]
name = "demo"
[[step]]
at = 1.0
caption = "first"
[[step]]
after = 0.5
target = "fastcat/2"
action = "unplug"
[[step]]
at = 1.5
target = "fastcat"
action = "hold_cnf"
seconds = 3.5
[[step]]
at = 2.0
checkpoint = "later"
""")
    assert [(s.t_us, s.kind) for s in sc.steps] == [
        (1_000_000, "caption"), (1_500_000, "command"), (1_500_000, "command"),
        (2_000_000, "checkpoint")]
    assert sc.steps[1].target == "fastcat/2" and sc.steps[1].action == "unplug"
    assert sc.steps[2].args == {"seconds": 3.5}
    assert sc.end_us == 3_000_000  # one second after the last step by default


def test_an_at_before_the_step_above_is_refused() -> None:
    """``at = 0.2`` under a step at 0.5 s is a slip (0.2 for 2.0, a pasted step): the steps
    were sorted silently, so the ``after`` steps below it counted from 0.2 s and the run failed
    at a later step for a reason far from the typo (the FastCAT's "object dictionary is
    generated at the end of the first internal-bus scan"), exit 1 after the whole run."""
    text = """
[[step]]
at = 0.5
caption = "first"
[[step]]
after = 1.0
checkpoint = "one"
[[step]]
at = 0.2
checkpoint = "typo"
"""
    with pytest.raises(ScenarioError, match=r"^bad.toml: step\[2\].at: 0.2 s is before "
                                            r"step\[1\] at 1.5 s \(steps are in time order"):
        parse_scenario(text, "bad.toml")


@pytest.mark.parametrize(("text", "message"), [
    ("[[step]]\nat = 1\n", "exactly one of caption, checkpoint, action"),
    ("[[step]]\nat = -1\ncaption = \"x\"\n", "must not be negative"),
    ("[[step]]\nat = 1\nafter = 1\ncaption = \"x\"\n", "not both"),
    ("[[step]]\naction = \"power\"\n", "needs target"),
    ("[[step]]\ncaption = \"\"\n", "must not be empty"),
    ("[[step]]\ncaption = \"x\"\ntarget = \"fastcat\"\n", "unknown key for a caption step"),
    ("[scenario]\nspeed = 2\n", "scenario.speed"),
    ("[scenario]\nlabel = \"  \"\n[[step]]\nat = 1\ncaption = \"x\"\n",
     "scenario.label: must not be empty"),
    ("[scenario]\nlabel = 3\n[[step]]\nat = 1\ncaption = \"x\"\n", "scenario.label"),
    ("[scenario]\nduration_s = 1\n[[step]]\nat = 5\ncaption = \"x\"\n", "before the last step"),
    ("step = 3\n", "array of tables"),
    ("[[step]\n", "not valid TOML"),
    ("rig = 1\n", "unknown key"),
])
def test_bad_scenarios(text: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(text, "bad.toml")


@pytest.mark.parametrize(("text", "message"), [
    ("", "no \\[scenario\\] table"),
    ("# only a comment\n", "no \\[scenario\\] table"),
    ("[scenario]\nname = \"x\"\n", "no steps"),
    ("[[step]]\nat = 0.0\ntarget = \"fastcat\"\naction = \"power\"\non = true\n",
     "no \\[scenario\\] table"),
])
def test_a_scenario_file_needs_its_table_and_steps(tmp_path, text: str, message: str) -> None:
    """A file without [scenario] or without a step is a wrong file (exit 2), not a run that
    passes (it exited 0, the last one even ran)."""
    from app.cli import main
    from app.scenario import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ScenarioError, match=message):
        load_scenario(path)
    assert main(["scenario", "run", str(path), "--quiet"]) == 2


@pytest.mark.parametrize(("text", "message"), [
    ("[[step]]\nat = 0.0\ntarget = \"fastcat\"\nacton = \"power\"\non = true\n",
     r"step\[0\]\.acton: unknown key \(known here: at, after, caption, checkpoint, focus, "
     r"target, action, expect_error\)"),
    ("[[step]]\nat = 0.0\ncaptoin = \"x\"\n", r"step\[0\]\.captoin: unknown key"),
    ("[[on]]\nevent = \"resync\"\ntarget = \"fastcat\"\nactoin = \"power\"\n",
     r"on\[0\]\.actoin: unknown key \(known here: event, slave, to, once, target, action\)"),
])
def test_a_typo_in_a_step_key_is_named(text: str, message: str) -> None:
    """``acton = "power"`` gave 'needs exactly one of caption, checkpoint, action' without
    naming the typo; rig files name it (``fastcat[0].box_nmae: unknown key``)."""
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(text, "bad.toml")


def test_steps_are_numbered_from_0_in_every_message() -> None:
    """One convention, the rig files' and [[on]]'s: ``step[N]`` from 0, parse and check
    alike (the check said ``step 1 (at 0 s)`` for the file's first step)."""
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import apply_step, check_against

    scenario = parse_scenario("[[step]]\nat = 0.5\ntarget = \"fastcat\"\naction = \"fly\"\n",
                              "bad.toml")
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    with pytest.raises(ScenarioError, match=r"bad.toml: step\[0\] \(at 0.5 s\): .*'fly'"):
        check_against(scenario, rig)
    refused = parse_scenario("[[step]]\nat = 0\ncaption = \"x\"\n[[step]]\nat = 0\n"
                             "target = \"fastcat\"\naction = \"power\"\non = true\n"
                             "expect_error = true\n", "bad.toml")
    failures: list[str] = []
    apply_step(refused.steps[1], rig, failures)
    assert failures == ["step[1] (at 0 s): expected an error, the command was accepted"]


@pytest.mark.parametrize(("step", "message"), [
    ('target = "fastcat"\naction = "inject_fault"\nfault = "NOT_A_FAULT"\n',
     r"step\[0\] \(at 1 s\): unknown fault 'NOT_A_FAULT'"),
    ('target = "drive"\naction = "write_parameter"\nparameter = "zz9"\nvalue = 3\n',
     r"step\[0\] \(at 1 s\): there is no parameter 'zz9'"),
    ('target = "trscat"\naction = "inject_fault"\nfault = "NO_SUCH"\n', r"step\[0\].*NO_SUCH"),
    ('target = "fastcat/12"\naction = "unplug"\n',
     r"step\[0\] \(at 1 s\): fastcat: no module at rail position 12"),
    ('target = "fastcat/17"\naction = "plug"\ntype = "DI16"\n', r"no rail position 17"),
])
def test_wrong_arguments_are_refused_before_the_run(tmp_path, capsys, step: str,
                                                    message: str) -> None:
    """Arguments the device's own tables refuse (a fault symbol, a parameter name, a rail
    position with no module) exited 1 at run time with a partial events.jsonl; docs promise
    they are checked before the run starts: exit 2, nothing written."""
    from app.cli import main
    from app.scenario import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(f"[scenario]\nname = \"x\"\n[[step]]\nat = 1.0\n{step}", encoding="utf-8")
    assert main(["scenario", "run", str(path), "--quiet", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("fieldrig: error: "), err
    assert not (tmp_path / "o" / "events.jsonl").exists()
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import check_against

    with pytest.raises(ScenarioError, match=message):
        check_against(load_scenario(path), build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))


def test_a_module_plugged_by_an_earlier_step_may_be_commanded() -> None:
    """Whether a rail position holds a module is the rail's state: a step that plugs one
    there (or swaps one there) comes first, then the position is a fine target."""
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import check_against

    scenario = parse_scenario(
        "[[step]]\nat = 0\ntarget = \"fastcat/9\"\naction = \"plug\"\ntype = \"DI16\"\n"
        "[[step]]\nat = 0\ntarget = \"fastcat/2\"\naction = \"swap\"\nother = 10\n"
        "[[step]]\nat = 1\ntarget = \"fastcat/9\"\naction = \"unplug\"\n"
        "[[step]]\nat = 1\ntarget = \"fastcat/10\"\naction = \"module_power\"\non = false\n",
        "ok.toml")
    check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))


def test_an_unknown_device_names_what_each_targetable_id_is() -> None:
    """The list gave every internal id bare (``drive-can``, ``drive_ec-ecat``, ...): a
    scenario may target them, but nothing said they are a drive's CANopen node or CoE
    slave."""
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import check_against

    scenario = parse_scenario('[[step]]\nat = 0\ntarget = "drives"\naction = "power"\n'
                              'on = true\n', "bad.toml")
    with pytest.raises(ScenarioError) as caught:
        check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    assert str(caught.value) == (
        "bad.toml: step[0] (at 0 s): no device 'drives' in rig 'FieldRig default rig' "
        "(devices: fastcat, trscat, cpx, drive, drive-can (the CANopen node of drive), "
        "drive_co, drive_co-can (the CANopen node of drive_co), drive_ec, drive_ec-can (the "
        "CANopen node of drive_ec), drive_ec-ecat (the EtherCAT CoE slave of drive_ec), "
        "master); did you mean 'drive'?")


@pytest.mark.parametrize(("line", "hint"), [
    ("fault = module:0x04", 'text values need quotes: fault = "module:0x04"'),
    ("name = Sales demo  # mine", 'text values need quotes: name = "Sales demo"'),
    ("on = True", "a yes/no value is true or false, lower case: on = true"),
    ("on = no", "a yes/no value is true or false, lower case: on = false"),
])
def test_an_invalid_toml_value_gets_a_hint(line: str, hint: str) -> None:
    """tomllib's "Invalid value (at line 3, column 9)" alone did not say what to change; its
    commonest cause is an unquoted text value. One line still."""
    text = f"[scenario]\nname = \"x\"\n{line}\n"
    with pytest.raises(ScenarioError) as exc:
        parse_scenario(text, "bad.toml")
    column = line.index("=") + 3
    assert str(exc.value) == f"bad.toml: not valid TOML: Invalid value (at line 3, column " \
                             f"{column}): {hint}"


@pytest.mark.parametrize(("line", "hint"), [
    ('modules = ["DB16", "DI16", DO16]',
     'text values need quotes: modules = ["DB16", "DI16", "DO16"]'),
    ("args = { on = True }", "a yes/no value is true or false, lower case: args = { on = true }"),
    ("values = [1, 2, x]", 'text values need quotes: values = [1, 2, "x"]'),
    ("fault = module:0x04", 'text values need quotes: fault = "module:0x04"'),
    ("on = True", "a yes/no value is true or false, lower case: on = true"),
    # every bare word of the line, so that the line shown parses
    ("y = [DO16, DI16]", 'text values need quotes: y = ["DO16", "DI16"]'),
    ("args = { on = True, off = no }",
     "a yes/no value is true or false, lower case: args = { on = true, off = false }"),
    ("name = Übung", 'text values need quotes: name = "Übung"'),
])
def test_the_hint_fixes_the_token_at_the_column(line: str, hint: str) -> None:
    """Only the bare word at tomllib's column is fixed: the hint quoted everything right of
    the first ``=`` (``modules = "["DB16", "DI16", DO16]"``), a fix that did not parse."""
    text = f"[scenario]\nname = \"x\"\n{line}\n"
    with pytest.raises(ScenarioError) as exc:
        parse_scenario(text, "bad.toml")
    assert str(exc.value).endswith(f"(at line 3, column {_bad_column(line)}): {hint}")
    fixed = hint.split(": ", 1)[1]
    tomllib.loads(fixed)  # the hint's line is valid TOML


def _bad_column(line: str) -> int:
    try:
        tomllib.loads(line)
    except tomllib.TOMLDecodeError as exc:
        return int(str(exc).rsplit("column ", 1)[1].rstrip(")"))
    raise AssertionError(f"{line} parses")


def test_a_line_that_cannot_parse_alone_gets_the_word_only() -> None:
    """A value continued from the line before: the line alone is no TOML, so the hint names
    the word to quote, not a fragment of a line (it showed ``"DO16",``)."""
    text = '[scenario]\nname = "x"\nmodules = ["DB16",\n  DO16,\n]\n'
    with pytest.raises(ScenarioError) as exc:
        parse_scenario(text, "bad.toml")
    assert str(exc.value).endswith('(at line 4, column 3): text values need quotes: "DO16"')


@pytest.mark.parametrize("line", ["x = [1, @b]", "x = -abc", "x = .5", "x = [1, -y]"])
def test_no_hint_when_the_column_is_not_a_bare_word(line: str) -> None:
    with pytest.raises(ScenarioError) as exc:
        parse_scenario(f"[scenario]\nname = \"x\"\n{line}\n", "bad.toml")
    assert str(exc.value).endswith(f"(at line 3, column {_bad_column(line)})")


def test_the_hint_is_for_invalid_values_only() -> None:
    with pytest.raises(ScenarioError) as exc:
        parse_scenario("[scenario]\nname = \"x\n", "bad.toml")
    assert str(exc.value) == "bad.toml: not valid TOML: Illegal character '\\n' (at line 2, " \
                             "column 10)"


def test_rig_and_exercise_files_get_the_hint_too() -> None:
    from app.classroom.exercise_file import split_exercise
    from app.rig_config import RigConfigError, parse_rig_spec

    with pytest.raises(RigConfigError, match=r'text values need quotes: type = "DI16"$'):
        parse_rig_spec("[rig]\ntype = DI16\n", "r.toml")
    with pytest.raises(ScenarioError, match=r'text values need quotes: fault = "x"$'):
        split_exercise("[exercise]\nfault = x\n", "e.toml")


def test_the_label_is_the_pickers_short_name_and_defaults_to_the_name() -> None:
    """``label``: what the Scenario picker's closed box shows of a long name."""
    text = "[scenario]\nname = \"A long title\"\n{}[[step]]\nat = 1\ncaption = \"x\"\n"
    assert parse_scenario(text.format("label = \"Short\"\n")).label == "Short"
    assert parse_scenario(text.format("")).label == "A long title"


def test_a_rig_the_scenario_names_that_is_not_there(tmp_path) -> None:
    """``rig = "nope.toml"`` said only "/abs/nope.toml: cannot read rig file" when the run, the
    dashboard's ``--scenarios`` check or ``scenario list`` got to it: with a folder of
    scenarios, nothing said which file named it. The scenario and its key are named now."""
    from app.scenario import load_scenario

    path = tmp_path / "demo.toml"
    path.write_text('[scenario]\nname = "d"\nrig = "nope.toml"\n[[step]]\nat = 0\n'
                    'caption = "x"\n', encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value) == (f"{path}: scenario.rig: 'nope.toml': no such rig file "
                               f"({tmp_path / 'nope.toml'}; a path relative to the scenario's "
                               "folder)")


@pytest.mark.parametrize(("text", "message"), [
    ("[[steps]]\nat = 0\ncaption = \"x\"\n", r"steps: unknown key .*; did you mean 'step'\?$"),
    ("[scenario]\nnmae = \"x\"\n", r"scenario\.nmae: unknown key .*did you mean 'name'\?$"),
    ("[[step]]\nat = 0.0\ntarget = \"fastcat\"\nacton = \"power\"\n",
     r"step\[0\]\.acton: unknown key .*; did you mean 'action'\?$"),
    ("[[step]]\nat = 0\ncaption = \"x\"\ncaptoin = \"y\"\n",
     r"step\[0\]\.captoin: unknown key for a caption step; did you mean 'caption'\?$"),
    # a command step (it has its action) whose target is misspelt: its other keys are the
    # action's arguments, and it read "a command step needs target" with no hint
    ("[[step]]\nat = 0\ntargt = \"fastcat\"\naction = \"power\"\non = true\n",
     r"step\[0\]\.targt: unknown key \(known here: .*\); did you mean 'target'\?$"),
    # the slip is named, not an argument that sorts before it, nor another slip
    ("[[step]]\nat = 0\naftr = 1\nTraget = \"fastcat\"\naction = \"power\"\non = true\n",
     r"step\[0\]\.Traget: unknown key \(known here: .*\); did you mean 'target'\?$"),
    ("[[step]]\nat = 0\ntarget = \"fastcat\"\nactoin = \"power\"\nactive = true\n",
     r"step\[0\]\.actoin: unknown key \(known here: .*\); did you mean 'action'\?$"),
    ("[[step]]\nat = 0\nfocus = \"fastcat\"\nfocsu = \"trscat\"\n",
     r"step\[0\]\.focsu: unknown key for a focus step; did you mean 'focus'\?$"),
    ("[[step]]\nat = 0\ncheckpoint = \"x\"\nchekpoint = \"y\"\n",
     r"step\[0\]\.chekpoint: unknown key for a checkpoint step; did you mean 'checkpoint'\?$"),
    ("[[on]]\nevent = \"resynch\"\ntarget = \"fastcat\"\naction = \"power\"\n",
     r"on\[0\]\.event: 'resynch' is not a master event .*; did you mean 'resync'\?$"),
    ("[[on]]\nevent = \"dc_state\"\nto = \"SYNCHRONIZNG\"\ntarget = \"fastcat\"\n"
     "action = \"power\"\n", r"on\[0\]\.to: .*; did you mean 'SYNCHRONIZING'\?$"),
])
def test_an_unknown_name_in_a_scenario_says_what_was_meant(text: str, message: str) -> None:
    """A walk-through: a typo was named, but the trainee still had to find the right word in
    the list; the closest allowed name is offered (devices/names.py did_you_mean)."""
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(text, "bad.toml")


def test_a_command_step_without_target_and_no_slip_still_says_it_needs_one() -> None:
    with pytest.raises(ScenarioError, match=r"step\[0\]: a command step needs target = "):
        parse_scenario('[[step]]\nat = 0\naction = "power"\non = true\n', "bad.toml")


@pytest.mark.parametrize(("text", "message"), [
    # a slip of an [[on]] key lands among the command's arguments: the action refuses it
    ('[[on]]\nevent = "resync"\nslav = "trscat"\ntarget = "master"\n'
     'action = "set_log_style"\nstyle = "twincat"\n',
     r"on\[0\]: action 'set_log_style' takes no argument slav .*; did you mean 'slave'\?$"),
    ('[[step]]\nat = 0\ntarget = "fastcat"\naction = "power"\non = true\n'
     'expct_error = true\n', r"takes no argument expct_error .*did you mean 'expect_error'\?$"),
    ('[[step]]\nat = 0\ntarget = "fastcat"\naction = "powr"\non = true\n',
     r"has no action 'powr' .*; did you mean 'power'\?$"),
    ('[[on]]\nevent = "resync"\nslave = "trscta"\ntarget = "master"\n'
     'action = "set_log_style"\nstyle = "twincat"\n',
     r"on\[0\]: no device 'trscta' .*; did you mean 'trscat'\?$"),
])
def test_an_unknown_argument_or_name_checked_against_the_rig_says_what_was_meant(
        text: str, message: str) -> None:
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import check_against

    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    with pytest.raises(ScenarioError, match=message):
        check_against(parse_scenario(text, "bad.toml"), rig)
