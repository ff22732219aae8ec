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


@pytest.mark.parametrize(("focus", "message"), [
    ("fastcat:30", r"step\[1\] \(at 1 s\): focus: fastcat has no module 30 \(modules: 1=DB16, "
                   r"3=DO16, .*7=AX2\); focus = \"fastcat\" is the device"),
    ("cpx:9", r"focus: cpx has no module 9 \(modules: 1=CPX-E-16DI, .*4=CPX-E-4AO-U-I\)"),
    ("drive:1", r"focus: drive has no modules: focus = \"drive\""),
    ("master:2", r"focus: master has no modules: focus = \"master\""),
    ("fastcat:2", r"focus: fastcat has no module 2 \(modules: 1=DB16, 3=DO16"),  # pulled at 0.5
], ids=["fastcat:30", "cpx:9", "drive:1", "master:2", "fastcat:2 pulled"])
def test_focus_on_a_module_the_device_does_not_hold_is_refused(focus: str,
                                                               message: str) -> None:
    """``focus = "fastcat:30"`` passed the check (the device only was looked up) and ran, exit
    0: a typo in a module number a scenario author never heard of."""
    scenario = parse_scenario("[[step]]\nat = 0.5\ntarget = \"fastcat/2\"\naction = \"unplug\"\n"
                              f"[[step]]\nat = 1\nfocus = \"{focus}\"\n", "f.toml")
    with pytest.raises(ScenarioError, match=message):
        check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG)))


def test_focus_on_a_module_an_earlier_step_plugs_is_taken() -> None:
    scenario = parse_scenario("[[step]]\nat = 0.5\ntarget = \"fastcat/9\"\naction = \"plug\"\n"
                              "type = \"DI16\"\n[[step]]\nat = 1\nfocus = \"fastcat:9\"\n"
                              "[[step]]\nat = 1\nfocus = \"trscat:2\"\n", "f.toml")
    check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG)))
