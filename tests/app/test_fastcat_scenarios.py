"""The FastCAT examples of session 23 show what seed 000 names: the SM2 watchdog (§7.7 0x001B,
docs/fastcat-coupler.md "SM watchdog") and the address check (§6.19 0x5301, §7.5 0x12,
§7.7 0x8012, "Address check"), at the pictures' instants."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import Step, load_scenario, run_scenario
from tests.app.test_line_scenarios import at, pick

SCENARIOS = Path(__file__).resolve().parents[2] / "static" / "scenarios"


def at_checkpoints(stem: str) -> dict[str, dict[str, Any]]:
    """The FastCAT's snapshot at each checkpoint of the example."""
    scenario = load_scenario(SCENARIOS / f"{stem}.toml")
    rig = build_rig(load_rig_spec(scenario.rig or DEFAULT_RIG))
    seen: dict[str, dict[str, Any]] = {}

    def keep(step: Step, rig: Rig) -> None:
        if step.kind == "checkpoint":
            seen[step.text] = rig.device("fastcat").snapshot()

    assert run_scenario(scenario, rig, on_step=keep).failures == []
    return seen


def test_sm_watchdog_drops_the_fastcat_to_safeop_with_0x001b_and_the_master_takes_it_back(
        ) -> None:
    name = "fastcat_sm_watchdog"
    lost = pick(name, "comm_error", "master", position=0)[0]["t"]
    fall = pick(name, "state", "fastcat", **{"from": "OP", "to": "SAFEOP"})
    assert [r["t"] for r in fall] == [round(lost + 0.1, 3)]  # 100 ms after the last frame
    t = fall[0]["t"]
    assert pick(name, "al_status", "fastcat", t=t, code="0x001B")
    assert pick(name, "led", "fastcat", t=t, led="ERR", pattern="double_flash")
    assert pick(name, "alarm", "fastcat") == [] and pick(name, "emergency", "fastcat") == []
    for slave in ("cpx", "drive_ec"):  # their watchdogs, as the caption says
        assert pick(name, "al_status", slave, t=t, code="0x001B")
    assert pick(name, "al_status", "trscat", code="0x001A")[0]["t"] < t  # its sync error
    master = [(r["from"], r["to"], r["code"]) for r in pick(name, "slave_state", "master",
                                                           position=0) if r["t"] > t]
    assert master == [("OP", "SAFEOP", "0x001B"), ("SAFEOP", "OP", "0x0000")]
    seen = at_checkpoints(name)
    do16 = {k: [i + 1 for i, on in enumerate(s["rail"][2]["do"]) if on] for k, s in seen.items()}
    assert do16 == {"outputs_on": [1, 3], "watchdog": [], "recovered": [1, 3]}
    assert [seen[k]["esm"] for k in ("outputs_on", "watchdog", "recovered")] == \
        ["OP", "SAFEOP", "OP"]


def test_address_check_raises_0x12_at_the_op_request_and_clears_on_reset() -> None:
    name = "fastcat_address_check"
    switch = pick(name, "read", "fastcat", address="0x5302:0")
    assert [r["value"] for r in switch] == [3]
    raised = pick(name, "alarm", "fastcat", code="0x12", active=True)
    assert len(raised) == 1
    t = raised[0]["t"]
    assert pick(name, "emergency", "fastcat", t=t, code="0xFF00", register="0x81",
                data="00 00 00 12 00")
    assert pick(name, "al_status", "fastcat", t=t, code="0x8012")
    assert pick(name, "state", "fastcat", t=t, **{"from": "SAFEOP", "to": "PREOP"})
    assert [r["hex"] for r in pick(name, "read", "fastcat", address="0x5400:0")] == \
        ["0x12000000"]
    assert at(name, "check_enabled") < t < at(name, "address_alarm")
    cleared = pick(name, "alarm", "fastcat", code="0x12", active=False)[0]["t"]
    back = pick(name, "state", "fastcat", **{"from": "SAFEOP", "to": "OP"})[-1]["t"]
    assert at(name, "address_alarm") < cleared < back < at(name, "recovered")
    seen = at_checkpoints(name)
    assert [(seen[k]["esm"], seen[k]["address_check"]) for k in seen] == [
        ("OP", True), ("PREOP", True), ("OP", False)]
