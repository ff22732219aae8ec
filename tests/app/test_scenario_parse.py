"""Scenario files: format and errors (issue 2 §4)."""

from __future__ import annotations

import pytest

from app.scenario import ScenarioError, parse_scenario


def test_steps_at_and_after_are_ordered() -> None:
    sc = parse_scenario("""
[scenario]
name = "demo"
[[step]]
at = 2.0
checkpoint = "later"
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
""")
    assert [(s.t_us, s.kind) for s in sc.steps] == [
        (1_000_000, "caption"), (1_500_000, "command"), (1_500_000, "command"),
        (2_000_000, "checkpoint")]
    assert sc.steps[1].target == "fastcat/2" and sc.steps[1].action == "unplug"
    assert sc.steps[2].args == {"seconds": 3.5}
    assert sc.end_us == 3_000_000  # one second after the last step by default


@pytest.mark.parametrize(("text", "message"), [
    ("[[step]]\nat = 1\n", "exactly one of caption, checkpoint, action"),
    ("[[step]]\nat = -1\ncaption = \"x\"\n", "must not be negative"),
    ("[[step]]\nat = 1\nafter = 1\ncaption = \"x\"\n", "not both"),
    ("[[step]]\naction = \"power\"\n", "needs target"),
    ("[[step]]\ncaption = \"\"\n", "must not be empty"),
    ("[[step]]\ncaption = \"x\"\ntarget = \"fastcat\"\n", "unknown key for a caption step"),
    ("[scenario]\nspeed = 2\n", "scenario.speed"),
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
