"""Module targets of every device are checked before the run, against the modules each
position holds at that step (the rig as built, changed by earlier plug / unplug / swap /
replace steps): a scenario that cannot work exits 2 with one line, before any event."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.cli import main


def run_steps(tmp_path: Path, steps: str, *flags: str) -> int:
    path = tmp_path / "s.toml"
    path.write_text(f"[scenario]\nname = \"t\"\nduration_s = 2\n{steps}", encoding="utf-8")
    return main(["scenario", "run", str(path), "--quiet", "--out", str(tmp_path / "o"), *flags])


def refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], steps: str,
            *flags: str) -> str:
    """The one stderr line of a scenario refused before the run (exit 2, no events.jsonl)."""
    rc = run_steps(tmp_path, steps, *flags)
    err = capsys.readouterr().err.splitlines()
    assert rc == 2, err
    assert len(err) == 1 and err[0].startswith("fieldrig: error: "), err
    assert not (tmp_path / "o" / "events.jsonl").exists()
    return err[0]


def step(target: str, action: str, at: float = 0.5, **args: object) -> str:
    lines = [f"[[step]]\nat = {at}\ntarget = \"{target}\"\naction = \"{action}\""]
    lines += [f"{k} = {v!r}".replace("'", '"').replace("True", "true").replace("False", "false")
              for k, v in args.items()]
    return "\n".join(lines) + "\n"


def test_a_cpx_module_that_is_not_there_is_refused_before_the_run(tmp_path, capsys) -> None:
    """cpx/7 on a four-module CPX-E-EC exited 1 at the step, events.jsonl half written."""
    line = refused(tmp_path, capsys, step("cpx/7", "inject_fault", fault="short_circuit"))
    assert line.endswith("s.toml: step[0] (at 0.5 s): cpx: no module 7 (modules: 1=16DI, "
                         "2=8DO, 3=4AI-U-I, 4=4AO-U-I)"), line


def test_a_cpx_short_circuit_without_a_module_is_refused_before_the_run(tmp_path,
                                                                         capsys) -> None:
    """target = "cpx" passed the check and the step failed with "no module None"."""
    line = refused(tmp_path, capsys, step("cpx", "inject_fault", fault="short_circuit"))
    assert line.endswith("step[0] (at 0.5 s): short_circuit needs a module: target 'cpx/N'"), \
        line


@pytest.mark.parametrize(("target", "action", "args"), [
    ("cpx/5", "set_input", {"channel": 0, "on": True}),
    ("cpx/9", "replace_module", {"type": "16DI"}),
])
def test_every_cpx_module_action_needs_a_module(tmp_path, capsys, target, action, args) -> None:
    line = refused(tmp_path, capsys, step(target, action, **args))
    assert f"cpx: no module {target[4:]} (modules: 1=16DI" in line, line


@pytest.mark.parametrize(("target", "action", "args", "message"), [
    ("trscat/3", "set_input", {"channel": 1, "on": True},
     "trscat: no expansion at position 3 (rail: 0=IO-B, 1=IO-E, 2=AN-E)"),
    ("trscat/5", "inject_fault", {"fault": "FIELD_SUPPLY"},
     "trscat: no expansion at position 5 (rail: 0=IO-B, 1=IO-E, 2=AN-E)"),
    ("trscat/8", "plug", {"type": "TRS-IO-E"}, "a TRS-CAT has expansion positions 1..7 (§5)"),
])
def test_a_trscat_expansion_that_is_not_there_is_refused(tmp_path, capsys, target, action,
                                                         args, message) -> None:
    line = refused(tmp_path, capsys, step(target, action, **args))
    assert line.endswith(f"step[0] (at 0.5 s): {message}"), line


def test_an_expansion_plugged_by_an_earlier_step_may_be_commanded(tmp_path, capsys) -> None:
    steps = (step("trscat", "power", at=0.0, on=False)
             + step("trscat/3", "plug", at=0.1, type="TRS-IO-E")
             + step("trscat/3", "set_input", at=0.2, channel=2, on=True))
    rc = run_steps(tmp_path, steps)
    assert rc == 0, capsys.readouterr().err


def test_a_position_an_on_command_may_fill_is_left_to_the_run() -> None:
    """An [[on]] command runs whenever its event comes: what it plugs may be there for any
    step, so the check does not refuse a step on that position."""
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import check_against, parse_scenario

    scenario = parse_scenario(
        step("trscat/4", "set_input", channel=1, on=True)
        + '[[on]]\nevent = "resync"\ntarget = "trscat/4"\naction = "plug"\n'
          'type = "TRS-IO-E"\n', "ok.toml")
    check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))


@pytest.mark.parametrize(("steps", "message"), [
    (step("fastcat/2", "plug", type="DI16"),
     "step[0] (at 0.5 s): fastcat: rail position 2 is taken by a DI16: unplug it first"),
    (step("fastcat/9", "plug", type="DI16") + step("fastcat/9", "plug", at=0.6, type="DO16"),
     "step[1] (at 0.6 s): fastcat: rail position 9 is taken by a DI16: unplug it first"),
    (step("fastcat/2", "swap", other=9) + step("fastcat/9", "plug", at=0.6, type="DO16"),
     "step[1] (at 0.6 s): fastcat: rail position 9 is taken by a DI16: unplug it first"),
    (step("trscat/1", "plug", type="TRS-IO-E"),
     "step[0] (at 0.5 s): trscat: position 1 holds a TRS-IO-E: unplug it first"),
])
def test_a_plug_on_a_taken_position_is_refused_before_the_run(tmp_path, capsys, steps,
                                                              message) -> None:
    """A plug on a position that holds a module by then (as built, or put there by an
    earlier plug or swap) passed the check and failed at the step (exit 1)."""
    line = refused(tmp_path, capsys, steps)
    assert line.endswith(message), line


def test_a_plug_after_an_unplug_of_the_same_position_is_fine(tmp_path, capsys) -> None:
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.scenario import check_against, parse_scenario

    scenario = parse_scenario(
        step("fastcat/2", "unplug") + step("fastcat/2", "plug", at=0.6, type="DO16")
        + step("trscat/2", "unplug", at=0.7) + step("trscat/2", "plug", at=0.8,
                                                     type="TRS-IO-E"), "ok.toml")
    check_against(scenario, build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))


def test_a_plug_the_trscat_cannot_fit_is_refused_before_the_run(tmp_path, capsys) -> None:
    """Seed 001 §5: with the TRS-IO-E and the TRS-AN-E, a third smart expansion does not fit;
    the earlier plugs count."""
    steps = "".join(step(f"trscat/{n}", "plug", at=0.1 * n, type="TRS-AC-E") for n in (3, 4, 5))
    line = refused(tmp_path, capsys, steps)
    assert "step[2] (at 0.5 s): 2 standard + 3 smart expansions do not fit a TRS-CAT" in line


@pytest.mark.parametrize("action", ["inject_fault", "clear_fault"])
@pytest.mark.parametrize("fault", ["module:0x04", "ALARM_IO_FAULT", "TARATURA"])
def test_a_fastcat_module_fault_on_the_coupler_is_refused_before_the_run(
        tmp_path, capsys, action, fault) -> None:
    """A module fault (§7.6) on target "fastcat" passed the check and failed only at run time,
    exit 1 after the whole run; the rule now sits in the model's check_command."""
    line = refused(tmp_path, capsys, step("fastcat", action, fault=fault))
    assert "step[0] (at 0.5 s): " in line and "is a module alarm (§7.6): target " \
        "'fastcat/N'" in line, line


def test_a_fastcat_module_fault_on_a_module_target_passes_the_check(tmp_path, capsys) -> None:
    steps = (step("fastcat", "power", at=0.0, on=True)
             + step("fastcat/3", "inject_fault", at=0.5, fault="module:0x04")
             + step("fastcat/3", "clear_fault", at=1.0, fault="module:0x04"))
    assert run_steps(tmp_path, steps) == 0, capsys.readouterr().err


@pytest.mark.parametrize(("steps", "message"), [
    (step("fastcat/8", "inject_fault", fault="TARATURA"),
     "step[0] (at 0.5 s): fastcat: TARATURA is a module alarm (§7.6): there is no module 8, "
     "rail position 8 is empty (modules: 1=DB16, 2=DI16, 3=DO16, 4=AI8D, 5=AO4, 6=AI8TC, "
     "7=AX2)"),
    (step("fastcat/5", "unplug", at=0.2) + step("fastcat/5", "inject_fault", fault="module:0x04"),
     "step[1] (at 0.5 s): fastcat: ALARM_IO_FAULT is a module alarm (§7.6): there is no "
     "module 5, rail position 5 is empty (modules: 1=DB16, 2=DI16, 3=DO16, 4=AI8D, 6=AI8TC, "
     "7=AX2)"),
])
def test_a_fastcat_module_fault_on_an_empty_position_is_refused_before_the_run(
        tmp_path, capsys, steps, message) -> None:
    """A §7.6 fault on an empty rail position passed the check and the run latched an alarm
    from a module that is not there."""
    line = refused(tmp_path, capsys, steps)
    assert line.endswith(message), line


def test_a_coupler_fault_on_an_empty_position_passes_the_check(tmp_path, capsys) -> None:
    """§7.5 0x02 MODULE_NO_PRES names a missing module: an empty position is its place."""
    steps = step("fastcat/8", "inject_fault", fault="MODULE_NO_PRES")
    assert run_steps(tmp_path, steps) == 0, capsys.readouterr().err


def on(target: str, action: str, **args: object) -> str:
    return step(target, action, **args).replace("[[step]]\nat = 0.5", "[[on]]\nevent = \"resync\"")


@pytest.mark.parametrize(("target", "action", "args", "said"), [
    ("cpx", "inject_fault", {"fault": "module_failure"},
     "module_failure needs a module: target 'cpx/N'"),
    ("trscat/1", "inject_fault", {"fault": "CONFIG_ERROR"},
     "CONFIG_ERROR is a fault of the TRS-CAT itself: target 'trscat'"),
    ("master", "pull_cable", {"cable": 9}, "cable 9: the line has positions 0..3"),
])
def test_an_on_command_any_rig_would_refuse_is_refused_before_the_run(
        tmp_path, capsys, target, action, args, said) -> None:
    """An [[on]] command is checked by check_command only (its modules are left to the run):
    these passed and failed when their event came, exit 1 after the run."""
    line = refused(tmp_path, capsys, step("master", "resync") + on(target, action, **args))
    assert line.endswith(f"on[0]: {said}"), line
