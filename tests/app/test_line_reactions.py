"""Scenario ``[[on]]`` tables: the master's ECAT_Notify hook driving commands (seed 003)."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError, check_against, parse_scenario, run_scenario

LINE_RIG = Path(__file__).resolve().parents[2] / "static" / "rigs" / "ethercat_line.toml"

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
    # A device of the rig that is no slave of the line: the reaction would never fire. The
    # drive on the line is its CoE side, as the rig file's line and the events' `slave` name
    # it; `slave = "drive_ec"` (the id its own events carry) was taken and never fired.
    (("slave = \"fastcat\"", "slave = \"drive_ec\""),
     "on\\[0\\].slave: 'drive_ec' is not a slave of the EtherCAT line \\(its slaves: fastcat, "
     "trscat, cpx, drive_ec-ecat; the EtherCAT side of drive_ec is 'drive_ec-ecat'\\)"),
    (("slave = \"fastcat\"", "slave = \"drive\""),
     "on\\[0\\].slave: 'drive' is not a slave of the EtherCAT line \\(its slaves: fastcat, "
     "trscat, cpx, drive_ec-ecat\\)$"),
])
def test_reactions_are_checked_against_the_rig(change: tuple[str, str], message: str) -> None:
    scenario = parse_scenario(GOOD.replace(*change), "r.toml")
    with pytest.raises(ScenarioError, match=message):
        check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG)))


RECOVERY = """
[scenario]
rig = "{rig}"
duration_s = 5
[[step]]
at = 4.0
target = "master"
action = "pull_cable"
cable = 2
[[step]]
at = 4.5
target = "master"
action = "plug_cable"
cable = 2
[[on]]
event = "network_recovery"
slave = "{slave}"
target = "master"
action = "set_log_style"
style = "sirio"
"""


@pytest.mark.parametrize(("slave", "fires"), [("cpx", True), ("drive_ec-ecat", True),
                                              ("trscat", False)])
def test_network_recovery_reaction_filters_on_the_recovered_slaves(slave: str,
                                                                   fires: bool) -> None:
    """``slave`` on a network_recovery: the slave is one of the event's ``positions``
    (docs/scenarios.md: "only events about this slave"). Cable 2 re-plugged recovers
    positions 2 and 3 (cpx, the drive); the TRS-CAT at 1 was never lost."""
    scenario = parse_scenario(RECOVERY.format(rig=LINE_RIG, slave=slave), "r.toml")
    rig = build_rig(load_rig_spec(LINE_RIG))
    run = run_scenario(scenario, rig)
    assert run.failures == []
    recoveries = [e for e in run.events if e.kind == "network_recovery"]
    assert [e.positions for e in recoveries] == [(2, 3)]  # type: ignore[attr-defined]
    lines = [e.text for e in run.events  # type: ignore[attr-defined]
             if e.device == "scenario" and e.kind == "log"]
    assert lines == (["on[0] network_recovery: master set_log_style"] if fires else [])
    assert rig.devices["master"].log_style == ("sirio" if fires else "twincat")


DC_STATE = """
[scenario]
rig = "{rig}"
duration_s = 4.5
[[step]]
at = 4.0
target = "master"
action = "dc_fault"
kind = "sync0_lost"
[[on]]
event = "dc_state"
to = "NOT_SYNCHRONIZED"
target = "master"
action = "set_log_style"
style = "sirio"
[[on]]
event = "dc_state"
target = "master"
action = "set_log_style"
style = "pegaso"
"""


def test_dc_state_reactions_follow_the_distributed_clock() -> None:
    """Seed 003 names "distributed clock status variation" among the ECAT_Notify events: a
    scenario reacts to the DC unit's moves, optionally to one state (``to``)."""
    scenario = parse_scenario(DC_STATE.format(rig=LINE_RIG), "r.toml")
    assert [(r.event, r.to) for r in scenario.reactions] == [
        ("dc_state", "NOT_SYNCHRONIZED"), ("dc_state", "")]
    run = run_scenario(scenario, build_rig(load_rig_spec(LINE_RIG)))
    assert run.failures == []
    moves = [e.to_state for e in run.events  # type: ignore[attr-defined]
             if e.kind == "state" and getattr(e, "machine", "") == "dc"]
    assert moves == ["SYNCHRONIZING", "WAITING_START_TIME", "COMPENSATING", "NOT_SYNCHRONIZED"]
    lines = [e.text for e in run.events  # type: ignore[attr-defined]
             if e.device == "scenario" and e.kind == "log"]
    assert lines == ["on[1] dc_state: master set_log_style"] * 3 + [
        "on[0] dc_state: master set_log_style", "on[1] dc_state: master set_log_style"]


@pytest.mark.parametrize(("extra", "message"), [
    ('to = "SYNCED"', "on\\[0\\].to: 'SYNCED' is not a DC state"),
    ('slave = "trscat"', "on\\[0\\].slave: a dc_state event is about the master"),
])
def test_bad_dc_state_reactions(extra: str, message: str) -> None:
    text = f'[[on]]\nevent = "dc_state"\n{extra}\ntarget = "master"\naction = "resync"\n'
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(text, "bad.toml")


def test_to_is_only_for_dc_state() -> None:
    text = '[[on]]\nevent = "resync"\nto = "OP"\ntarget = "master"\naction = "resync"\n'
    with pytest.raises(ScenarioError, match=r'on\[0\]\.to: only for event = "dc_state"'):
        parse_scenario(text, "bad.toml")
