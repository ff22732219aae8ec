"""Scenario ``focus`` steps: parsed, checked against the rig, emitted as Focus events."""

from __future__ import annotations

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError, check_against, parse_scenario, run_scenario
from devices.events import Focus

FOCUS = """
[[step]]
at = 0.5
focus = "fastcat"
[[step]]
after = 0.5
focus = "fastcat/2"
[[step]]
after = 0.0
focus = "fastcat:3"
"""


def test_focus_steps_emit_focus_records() -> None:
    scenario = parse_scenario(FOCUS)
    assert [(s.kind, s.target) for s in scenario.steps] == [
        ("focus", "fastcat"), ("focus", "fastcat:2"), ("focus", "fastcat:3")]
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    run = run_scenario(scenario, rig)
    records = [e.to_record() for e in run.events if isinstance(e, Focus)]
    assert records == [
        {"t": 0.5, "device": "scenario", "event": "focus", "target": "fastcat"},
        {"t": 1.0, "device": "scenario", "event": "focus", "target": "fastcat:2"},
        {"t": 1.0, "device": "scenario", "event": "focus", "target": "fastcat:3"}]
    assert run.failures == []


def test_focus_on_a_device_not_in_the_rig_is_refused_before_the_run() -> None:
    scenario = parse_scenario("[[step]]\nat = 1\nfocus = \"nosuch\"\n", "f.toml")
    with pytest.raises(ScenarioError, match=r"step\[0\].*no device 'nosuch'"):
        check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG)))


@pytest.mark.parametrize(("text", "message"), [
    ("[[step]]\nfocus = \"a b\"\n", "step\\[0\\].focus"),
    ("[[step]]\nfocus = \"fastcat:0\"\n", "numbered from 1"),
    ("[[step]]\nfocus = \"fastcat\"\ntarget = \"fastcat\"\n", "unknown key for a focus step"),
    ("[[step]]\nfocus = \"x\"\ncaption = \"y\"\n", "exactly one of"),
])
def test_bad_focus_steps(text: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(text, "bad.toml")
