"""Exercises and their scoring (issue 6 "exercise mode"; docs/classroom.md "Scoring"): the
rules are data, the causes and faults come from the devices' code tables (seed 000 §7.5, §7.6,
the drive manual's alarm table)."""

from __future__ import annotations

from typing import Any

import pytest

from app.classroom.exercise import Exercise, Phase
from app.classroom.faults import catalog, fault_gone, other_faults
from app.classroom.scoring import RULES, ScoringRules, score, time_points
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.panels.classroom_html import history_html, trainee_html
from devices.device import CommandError
from devices.fastcat.alarms import CODE_TABLES


@pytest.mark.parametrize(("seconds", "points"), [
    (0.0, 20), (RULES.par_s, 20), ((RULES.par_s + RULES.limit_s) / 2, 10),
    (RULES.limit_s, 0), (10 * RULES.limit_s, 0)])
def test_time_points(seconds: float, points: int) -> None:
    assert time_points(RULES, seconds) == points


@pytest.mark.parametrize(("right", "fixed", "seconds", "actions", "refused", "total"), [
    (True, True, 30.0, 2, 0, 100),
    (True, True, 30.0, 8, 0, 95),  # 5 commands beyond the 3 free ones
    (True, True, 30.0, 40, 0, 90),  # the action penalty is capped at 10
    (True, True, 30.0, 5, 2, 96),  # 2 refused: -4, 3 allowed are free
    (True, False, 30.0, 2, 0, 50),  # time counts for a working fix only
    (False, True, 30.0, 2, 0, 30),
    (False, False, 30.0, 2, 9, 0),  # never below 0
    (True, True, 360.0, 0, 0, 90),
])
def test_score(right: bool, fixed: bool, seconds: float, actions: int, refused: int,
               total: int) -> None:
    result = score(cause_right=right, fixed=fixed, seconds=seconds, actions=actions,
                   refused=refused)
    assert result.total == total
    assert result.maximum == 100
    assert sum(p.points for p in result.parts) == total or total == 0


def test_rules_are_checked() -> None:
    with pytest.raises(ValueError):
        ScoringRules(par_s=100.0, limit_s=50.0)
    custom = ScoringRules(cause_points=10, fixed_points=10, time_points=0)
    assert score(cause_right=True, fixed=True, seconds=1.0, actions=0, refused=0,
                 rules=custom).total == 20


@pytest.fixture(scope="module")
def rig_catalog() -> Any:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    return catalog(rig.describe(), rig.snapshot())


def test_causes_come_from_the_code_tables(rig_catalog: Any) -> None:
    ids = {c.id for c in rig_catalog.causes}
    for table in CODE_TABLES.values():  # §7.5 and §7.6
        for row in table.values():
            assert f"fastcat:{row.label}" in ids
    assert "drive:alarm:16" in ids  # FOLLOWING_ERROR of the drive's alarm table
    for fault in rig_catalog.faults:
        assert rig_catalog.cause(fault.cause) is not None, fault.id


def _powered_rig() -> Rig:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.apply("fastcat", "power", {"on": True})
    rig.apply("master", "set_target", {"state": "OP"})
    rig.run_until(3_000_000)
    return rig


def _run(rig: Rig, commands: Any) -> None:
    for c in commands:
        rig.apply(c.target, c.action, dict(c.args))


@pytest.mark.parametrize(("fault_id", "module"), [
    ("fastcat:inject:coupler:0x04", None), ("fastcat:inject:module:0x0B", 5),
    ("fastcat:cable", None)])
def test_exercise_right_cause_fixed(rig_catalog: Any, fault_id: str, module: int | None) -> None:
    rig = _powered_rig()
    fault = rig_catalog.fault(fault_id).at(module)
    assert fault_gone(fault, rig.snapshot())
    _run(rig, fault.inject)
    rig.run_until(rig.clock.now_us + 500_000)
    assert not fault_gone(fault, rig.snapshot())
    exercise = Exercise(fault, started_s=100.0)
    exercise.record(101.0, 4, "trainee", "fastcat: inject_fault", refused="instructor only")
    exercise.record(102.0, 4, "trainee", "fastcat: set_reset_fault on=True")
    assert exercise.name_cause(130.0, fault.cause, client_id=4) is True
    assert exercise.phase is Phase.ANSWERED
    with pytest.raises(ValueError):
        exercise.name_cause(131.0, fault.cause)
    _run(rig, fault.repair)
    # The alarm stays latched until the trainee resets it (§7: 0x5200:1 rising edge).
    rig.run_until(rig.clock.now_us + 100_000)
    assert not fault_gone(fault, rig.snapshot())
    rig.apply("fastcat", "set_reset_fault", {"on": True})
    rig.run_until(rig.clock.now_us + 100_000)
    result = exercise.finish(160.0, rig.snapshot())
    assert exercise.fixed, rig.snapshot()["devices"]["fastcat"]["alarm"]
    assert result.total == 100 - 2  # one refused command
    exercise.record(170.0, 4, "trainee", "late")
    assert len(exercise.actions) == 2
    report = exercise.report(rig_catalog)
    assert report["right"] and report["score"]["total"] == result.total
    assert report["actions"][0]["refused"]


def test_exercise_wrong_cause(rig_catalog: Any) -> None:
    rig = _powered_rig()
    fault = rig_catalog.fault("fastcat:inject:coupler:0x04")
    _run(rig, fault.inject)
    rig.run_until(rig.clock.now_us + 500_000)
    exercise = Exercise(fault, started_s=0.0)
    assert exercise.name_cause(10.0, "fastcat:coupler:0x13") is False
    result = exercise.finish(20.0, rig.snapshot())
    assert not exercise.fixed and result.total == 0
    assert [p.rule for p in result.parts][:3] == ["cause", "fixed", "time"]
    assert result.parts[0].why == "named another cause"
    assert history_html([exercise.report(rig_catalog)]).count("<td>wrong</td>") == 1


def test_exercise_ended_with_no_answer_says_so(rig_catalog: Any) -> None:
    """End and score before any answer read "named another cause" and "wrong"."""
    rig = _powered_rig()
    exercise = Exercise(rig_catalog.fault("fastcat:inject:coupler:0x04"), started_s=0.0)
    result = exercise.finish(20.0, rig.snapshot())
    assert result.parts[0].points == 0 and result.parts[0].why == "no cause named"
    assert "<td>none named</td>" in history_html([exercise.report(rig_catalog)])


def _every_fault() -> list[str]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    return [f.id for f in catalog(rig.describe(), rig.snapshot()).faults]


@pytest.fixture(scope="module")
def all_powered() -> Rig:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for device_id, info in rig.describe().items():
        if "power" in info["actions"]:
            rig.apply(device_id, "power", {"on": True})
    rig.run_until(10_000)
    return rig


@pytest.mark.parametrize("fault_id", _every_fault())
def test_every_hidden_fault_injects_and_repairs(rig_catalog: Any, all_powered: Rig,
                                                fault_id: str) -> None:
    """Each fault of the picker is a real command pair of its model (on the first module it
    fits, for module faults), and its cause is one of the candidates."""
    rig = all_powered  # one rig for all: each test removes the cause it made
    base = rig_catalog.fault(fault_id)
    for module in range(1, 9) if base.module else (None,):
        fault = base.at(module)
        try:
            _run(rig, fault.inject)
            break
        except CommandError:  # a module fault fits some module types only (the model says)
            continue
    else:
        pytest.fail(f"{fault_id} fits no module of the default rig")
    rig.run_until(rig.clock.now_us + 10_000)
    _run(rig, fault.repair)
    assert rig_catalog.cause(fault.cause) is not None


def test_only_the_page_that_answered_reads_answer_recorded(rig_catalog: Any) -> None:
    """A second trainee, whose answer was refused, read "Answer recorded" too."""
    exercise = Exercise(rig_catalog.fault("fastcat:inject:coupler:0x04"), started_s=0.0)
    exercise.name_cause(5.0, "fastcat:coupler:0x13", client_id=4)
    report = exercise.report(rig_catalog)
    assert report["answered_by"] == 4
    assert "Answer recorded" in trainee_html(report, 6.0, mine=True)
    other = trainee_html(report, 6.0, mine=False)
    assert "Answer recorded" not in other and "Another trainee named a cause" in other


def test_another_fault_on_the_device_does_not_cost_the_fix(rig_catalog: Any) -> None:
    """docs/classroom.md "fault_gone": the exercise's own fault is scored. A second fault the
    instructor put on the same device (the cable pulled) cost the trainee the 30 points and
    read "the rig still shows the fault"; it is named in the result instead."""
    rig = _powered_rig()
    fault = rig_catalog.fault("fastcat:inject:coupler:0x04")
    other = rig_catalog.fault("fastcat:cable")
    _run(rig, fault.inject)
    rig.run_until(rig.clock.now_us + 500_000)
    exercise = Exercise(fault, started_s=0.0)
    assert exercise.name_cause(10.0, fault.cause) is True
    _run(rig, fault.repair)
    _run(rig, other.inject)
    rig.run_until(rig.clock.now_us + 500_000)
    rig.apply("fastcat", "set_reset_fault", {"on": True})
    rig.run_until(rig.clock.now_us + 500_000)
    shown = rig.snapshot()["devices"]["fastcat"]["alarm"]
    assert shown["name"] == "LINK_LOSS", shown
    assert fault_gone(fault, rig.snapshot())
    assert not fault_gone(other, rig.snapshot())
    result = exercise.finish(20.0, rig.snapshot())
    fixed = next(p for p in result.parts if p.rule == "fixed")
    assert exercise.fixed and fixed.points == RULES.fixed_points and result.total == 100
    assert fixed.why == "the fault is gone; another fault is still present: fastcat LINK_LOSS"
    assert exercise.report(rig_catalog)["others"] == ["fastcat LINK_LOSS"]


@pytest.mark.parametrize(("shown", "gone", "others"), [
    ({"alarm": {"code": 1, "name": "IGBT"}, "alarms": [1],
      "injected": [{"code": 1, "name": "IGBT"}]}, True, ["drive IGBT"]),
    ({"alarm": {"code": 16, "name": "FOLLOWING_ERROR"}, "alarms": [16, 1],
      "injected": [{"code": 1, "name": "IGBT"}]}, False, ["drive IGBT"]),
    ({"alarm": None, "alarms": [], "injected": [{"code": 16, "name": "FOLLOWING_ERROR"}]},
     False, []),
])
def test_own_fault_of_a_drive(rig_catalog: Any, shown: dict[str, Any], gone: bool,
                              others: list[str]) -> None:
    """A drive shows several alarms: its own code shown, or its cause still injected, is
    not gone; another alarm is another fault."""
    fault = rig_catalog.fault("drive:inject:alarm:16")
    snapshot = {"devices": {"drive": shown}}
    assert fault_gone(fault, snapshot) is gone
    assert other_faults(fault, snapshot) == others


def _finish_fixed(fault: Any, rig: Rig) -> Any:
    exercise = Exercise(fault, started_s=0.0)
    assert exercise.name_cause(10.0, fault.cause) is True
    result = exercise.finish(20.0, rig.snapshot())
    return exercise, next(p for p in result.parts if p.rule == "fixed")


def test_own_fault_of_the_cpx(rig_catalog: Any) -> None:
    """The CPX-E-EC's injected entries were labels ("module_ident_mismatch module 2"), which
    never equalled the fault's name: the fault read gone while injected (30 points for
    nothing) and was named as "another fault". Its entries are {fault, module, ...} now."""
    rig = _powered_rig()
    base = rig_catalog.fault("cpx:inject:fault:module_ident_mismatch")
    fault, other = base.at(2), base.at(3)
    _run(rig, fault.inject)
    rig.run_until(rig.clock.now_us + 100_000)
    assert not fault_gone(fault, rig.snapshot())
    assert other_faults(fault, rig.snapshot()) == []
    _run(rig, other.inject)  # the same fault on another module is another fault
    _run(rig, fault.repair)
    rig.run_until(rig.clock.now_us + 100_000)
    assert fault_gone(fault, rig.snapshot())
    assert not fault_gone(other, rig.snapshot())
    exercise, fixed = _finish_fixed(fault, rig)
    assert exercise.fixed and fixed.points == RULES.fixed_points
    assert exercise.others == ["cpx module_ident_mismatch module 3"]


@pytest.mark.parametrize("fault_id", ["cpx:inject:fault:module_failure@2",
                                      "cpx:inject:fault:short_circuit@1"])
def test_a_cpx_physical_fault_is_present_while_the_module_has_it(rig_catalog: Any,
                                                                 fault_id: str) -> None:
    """module_failure and short_circuit set a module's condition and were never in the CPX
    snapshot's injected list: the failure read gone while the module still failed."""
    rig = _powered_rig()
    fault = rig_catalog.fault(fault_id)
    _run(rig, fault.inject)
    rig.run_until(rig.clock.now_us + 100_000)
    assert not fault_gone(fault, rig.snapshot())
    assert other_faults(fault, rig.snapshot()) == []
    _run(rig, fault.repair)
    rig.run_until(rig.clock.now_us + 100_000)
    assert fault_gone(fault, rig.snapshot())


TWO_AN_E = """[rig]
name = "two TRS-AN-E"

[[trscat]]
id = "trscat"
expansions = ["TRS-AN-E", "TRS-AN-E"]
configured = ["TRS-AN-E", "TRS-AN-E"]
"""


def test_a_trscat_fault_on_another_slot_is_another_fault(tmp_path: Any) -> None:
    """A TRS-CAT module fault was matched by its name only: the same fault on the other
    TRS-AN-E counted as the exercise's own (not gone, and never named as another)."""
    path = tmp_path / "two_an_e.toml"
    path.write_text(TWO_AN_E)
    rig = build_rig(load_rig_spec(path), state_dir=None)
    rig.apply("trscat", "power", {"on": True})
    rig.run_until(1_000_000)
    base = catalog(rig.describe(), rig.snapshot()).fault("trscat:inject:fault:AN_PLUS_12V")
    fault, other = base.at(1), base.at(2)
    _run(rig, fault.inject)
    rig.run_until(rig.clock.now_us + 100_000)
    assert not fault_gone(fault, rig.snapshot())
    assert other_faults(fault, rig.snapshot()) == []
    _run(rig, other.inject)
    _run(rig, fault.repair)
    rig.run_until(rig.clock.now_us + 100_000)
    assert fault_gone(fault, rig.snapshot())
    assert not fault_gone(other, rig.snapshot())
    exercise, fixed = _finish_fixed(fault, rig)
    assert exercise.fixed and fixed.points == RULES.fixed_points
    assert exercise.others == ["trscat AN_PLUS_12V slot 2"]
