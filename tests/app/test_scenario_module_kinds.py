"""A step whose action or arguments do not fit the kind of module its target holds at that
step (an encoder action on an analog module, a channel the module does not have, a fault its
kind cannot have) is refused before the run (exit 2, one line), in the step's own words."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.cli import main
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError, check_against, parse_scenario

ROOT = Path(__file__).resolve().parents[2]


def step(target: str, action: str, at: float = 0.5, **args: object) -> str:
    text = [f"[[step]]\nat = {at}\ntarget = \"{target}\"\naction = \"{action}\""]
    for key, value in args.items():
        shown = ("true" if value else "false") if isinstance(value, bool) else \
            f"\"{value}\"" if isinstance(value, str) else str(value)
        text.append(f"{key} = {shown}")
    return "\n".join(text) + "\n"


def check(text: str) -> None:
    check_against(parse_scenario(text, "s.toml"),
                  build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))


def test_an_encoder_scenario_on_a_rig_without_the_encoder_exits_2(tmp_path, capsys) -> None:
    """ax2_homing.toml with --rig nine_analog.toml (module 7 is an AB4P4, not the AX2) ran
    and failed at 4.5 s (exit 1, events.jsonl half written) for a step the check could read
    from the rig: set_shaft_speed on a module without encoder inputs."""
    out = tmp_path / "o"
    rc = main(["scenario", "run", str(ROOT / "static/scenarios/ax2_homing.toml"), "--quiet",
               "--rig", str(ROOT / "static/rigs/nine_analog.toml"), "--out", str(out)])
    err = capsys.readouterr().err.splitlines()
    assert rc == 2, err
    assert len(err) == 1 and err[0].endswith(
        "ax2_homing.toml: step[2] (at 4.5 s): action 'set_shaft_speed' needs a module with "
        "encoder inputs; AB4P4 is '4 potentiometer inputs, 4 analog outputs'"), err
    assert not (out / "events.jsonl").exists()


@pytest.mark.parametrize(("text", "message"), [
    (step("fastcat/2", "output_short", channel=1, active=True),
     "action 'output_short' needs a module with digital outputs; DI16 is '16 digital inputs'"),
    (step("fastcat/6", "wire_thermocouple", channel=9, type="K"),
     "AI8TC has thermocouple channels 1..8, not 9"),
    (step("fastcat/2", "unplug") + step("fastcat/2", "plug", at=0.6, type="AI4D")
     + step("fastcat/2", "set_input", at=0.7, channel=1, value=True),
     r"step\[2\] \(at 0.7 s\): action 'set_input' needs a module with digital inputs; AI4D"),
    (step("cpx/2", "set_input", channel=0, on=True),
     r"module 2 \(CPX-E-8DO\) has no digital inputs"),
    (step("cpx/2", "short_circuit", channel=9, on=True), r"CPX-E-8DO has channels 0 ... 7, not 9"),
    (step("cpx/1", "inject_fault", fault="wire_break", channel=0),
     "CPX-E-16DI: wire break is diagnosed on analog channels and the counter input"),
    (step("cpx/3", "force", channel=0, value=1), "CPX-E-4AI-U-I: only digital channels"),
    (step("trscat/1", "set_analog_input", channel=1, volts=2.0),
     "TRS-IO-E has no analog channels"),
    (step("trscat/2", "set_output", channel=3, value=5), "TRS-AN-E: channel 3 outside 1..2"),
    (step("trscat", "set_output", channel=1, value=2), "output 1: 2 outside 0..1"),
    (step("trscat/1", "inject_fault", fault="AN_PLUS_12V"),
     r"AN_PLUS_12V \(0x5114\) is a TRS-AN-E fault; position 1 is a TRS-IO-E"),
])
def test_an_action_that_does_not_fit_the_module_is_refused(text: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        check(text)


def test_a_module_replaced_by_an_earlier_step_is_checked_as_its_new_kind() -> None:
    check(step("cpx/2", "replace_module", type="16DI")
          + step("cpx/2", "set_input", at=0.6, channel=3, on=True))
    check(step("fastcat/2", "swap", other=4)  # the AI8D comes to 2, the DI16 to 4
          + step("fastcat/4", "set_input", at=0.6, channel=3, value=True))
