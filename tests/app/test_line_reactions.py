"""Scenario ``[[on]]`` tables: the master's ECAT_Notify hook driving commands (seed 003)."""

from __future__ import annotations

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError, check_against, parse_scenario

GOOD = """
[[on]]
event = "resync"
slave = "fastcat"
once = true
target = "fastcat"
action = "write_object"
index = 0x5200
sub = 1
value = 0
[[step]]
at = 1
caption = "x"
"""


def test_reaction_is_parsed_with_its_arguments() -> None:
    (r,) = parse_scenario(GOOD).reactions
    assert (r.number, r.event, r.slave, r.target, r.action, r.once) == (
        1, "resync", "fastcat", "fastcat", "write_object", True)
    assert r.args == {"index": 0x5200, "sub": 1, "value": 0}


@pytest.mark.parametrize(("text", "message"), [
    ("on = 3\n", "array of tables"),
    ("[[on]]\nevent = \"boom\"\ntarget = \"x\"\naction = \"y\"\n", "not a master event"),
    ("[[on]]\nevent = \"resync\"\n", "needs target"),
    ("[[on]]\nevent = \"resync\"\ntarget = \"x\"\naction = \"y\"\nonce = 1\n", "on\\[0\\].once"),
])
def test_bad_reactions(text: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(text, "bad.toml")


@pytest.mark.parametrize(("change", "message"), [
    (("action = \"write_object\"", "action = \"fly\""), "on\\[0\\]"),
    (("slave = \"fastcat\"", "slave = \"nosuch\""), "no device 'nosuch'"),
])
def test_reactions_are_checked_against_the_rig(change: tuple[str, str], message: str) -> None:
    scenario = parse_scenario(GOOD.replace(*change), "r.toml")
    with pytest.raises(ScenarioError, match=message):
        check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG)))
