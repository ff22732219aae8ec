"""An exercise file's ``channel = N`` (docs/classroom.md "Exercise files"): a hidden short on
a CPX-E-EC output channel (seed 002 §2.5.3 Tab. 21-23, KZA). Before, the ``[exercise]`` table
had no channel key and the 8DO refused ``short_circuit`` without one ("give the output
channel"): only the sensor-supply short (KZS) could be set from a file."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_classroom_exercise_file import run_until_started

from app.classroom.exercise_file import ExerciseSpec, check_exercise, load_exercise, parse_spec
from app.classroom.faults import Catalog, HiddenFault, catalog, fault_gone, other_faults
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError

FILE = """\
[scenario]
name = "Outputs on"
duration_s = 1

[[step]]
at = 0.0
target = "cpx"
action = "power"
on = true

[exercise]
fault = "{fault}"
{keys}
"""
SHORT = "cpx:inject:fault:short_circuit"


@pytest.fixture
def rig() -> Rig:
    return build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)


def _faults(rig: Rig) -> Catalog:
    return catalog(rig.describe(), rig.snapshot())


def _check(tmp_path: Path, rig: Rig, keys: str, fault: str = SHORT) -> HiddenFault:
    path = tmp_path / "ex.toml"
    path.write_text(FILE.format(fault=fault, keys=keys))
    scenario, spec = load_exercise(path)
    return check_exercise(scenario, spec, rig, _faults(rig))


def test_spec_reads_the_channel() -> None:
    assert parse_spec({"fault": "f", "module": 2, "channel": 0}) == \
        ExerciseSpec("f", 2, None, 0)


@pytest.mark.parametrize(("table", "said"), [
    ({"fault": "f", "module": 2, "channel": -1}, "exercise.channel: a channel number from 0"),
    ({"fault": "f", "module": 2, "channel": True}, "exercise.channel: a channel number"),
    ({"fault": "f", "channel": 3}, "exercise.channel: give its module too: module = N"),
])
def test_bad_channel(table: dict[str, object], said: str) -> None:
    with pytest.raises(ScenarioError) as caught:
        parse_spec(table)
    assert said in str(caught.value)


def test_an_output_short_passes_the_start_check_with_its_channel(tmp_path: Path,
                                                                  rig: Rig) -> None:
    fault = _check(tmp_path, rig, "module = 2\nchannel = 3")
    assert [(c.target, dict(c.args)) for c in fault.inject] == \
        [("cpx/2", {"fault": "short_circuit", "channel": 3})]
    assert [(c.target, dict(c.args)) for c in fault.repair] == \
        [("cpx/2", {"fault": "short_circuit", "channel": 3})]
    assert fault.id == f"{SHORT}@2.3" and "module 2, channel 3" in fault.label
    assert _faults(rig).fault(fault.id) == fault


def test_without_channel_the_8do_names_the_key(tmp_path: Path, rig: Rig) -> None:
    with pytest.raises(ScenarioError) as caught:
        _check(tmp_path, rig, "module = 2")
    said = str(caught.value)
    assert "no sensor supply to short" in said and "channel = N" in said, said


@pytest.mark.parametrize(("keys", "said"), [
    ("module = 2\nchannel = 9", "module 2 channel 9: CPX-E-8DO has channels 0 ... 7, not 9"),
    ("module = 1\nchannel = 3", "module 1 channel 3: CPX-E-16DI has no outputs to short"),
])
def test_a_channel_the_module_does_not_have_is_one_line(tmp_path: Path, rig: Rig, keys: str,
                                                        said: str) -> None:
    with pytest.raises(ScenarioError) as caught:
        _check(tmp_path, rig, keys)
    text = str(caught.value)
    assert said in text and text.startswith(f"{tmp_path / 'ex.toml'}: [exercise]") \
        and "\n" not in text, text


def test_a_fault_that_takes_no_channel_refuses_one(tmp_path: Path, rig: Rig) -> None:
    """module_failure ignores a channel: the fault would have been scored as not its own."""
    with pytest.raises(ScenarioError, match=r"exercise\.channel: .*module_failure.* takes no "
                                            r"channel"):
        _check(tmp_path, rig, "module = 2\nchannel = 3", "cpx:inject:fault:module_failure")


def test_scoring_matches_the_channel(rig: Rig) -> None:
    """The short on channel 3 is the exercise's own; one on channel 5, or the same channel
    of another module, is another fault, as a module fault on another module is."""
    fault = _faults(rig).fault(f"{SHORT}@2.3")
    for command in fault.inject:
        rig.apply(command.target, command.action, dict(command.args))
    rig.apply("cpx/2", "short_circuit", {"on": True, "channel": 5})
    snap = rig.snapshot()
    assert not fault_gone(fault, snap)
    assert other_faults(fault, snap) == ["cpx short_circuit module 2 channel 5"]
    for command in fault.repair:
        rig.apply(command.target, command.action, dict(command.args))
    snap = rig.snapshot()
    assert fault_gone(fault, snap)
    assert not fault_gone(_faults(rig).fault(f"{SHORT}@2.5"), snap)


def test_play_file_and_start_shorts_that_channel(tmp_path: Path, rig: Rig) -> None:
    """The served path: the injection thread gets the file's channel, not only its module."""
    from app.classroom.roles import Access
    from app.ui.panels.classroom_rig import serve_rig

    path = tmp_path / "short.toml"
    path.write_text(FILE.format(fault=SHORT, keys="module = 2\nchannel = 3\nat_s = 0.5"))
    served = serve_rig(rig, Access(None), port=0, paused=True, exercise_files=[path])
    try:
        classroom = served.classroom
        classroom.start_from_file(path)
        run_until_started(served, 1_000_000)
        assert classroom.exercise.fault.id == f"{SHORT}@2.3"
        snap = served.runtime.submit(served.runtime.rig.snapshot).result(timeout=10)
        assert {"fault": "short_circuit", "module": 2, "channel": 3, "sm": None} in \
            snap["devices"]["cpx"]["injected"]
    finally:
        served.stop()
