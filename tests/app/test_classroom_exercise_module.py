"""An exercise file's ``module = N`` on a fault that is put on no module (docs/classroom.md
"Exercise files"): one line at the start check, as for a channel. Before, the module was
dropped without a word: the doc's own example, ``fastcat:inject:coupler:0x04`` with
``module = 3``, injected the coupler's 0x04 with no node named (AL status code 0x8004,
"coupler: coupler code 0x04") on a rig whose instructor had asked for module 3."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_classroom_exercise_channel import _check

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import ScenarioError


@pytest.fixture
def rig() -> Rig:
    return build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)


@pytest.mark.parametrize("fault", ["fastcat:inject:coupler:0x04", "fastcat:cable"])
def test_a_fault_on_no_module_refuses_a_module(tmp_path: Path, rig: Rig, fault: str) -> None:
    with pytest.raises(ScenarioError) as caught:
        _check(tmp_path, rig, "module = 3", fault)
    said = str(caught.value)
    assert said.startswith(f"{tmp_path / 'ex.toml'}: exercise.module: ") and "\n" not in said
    assert f"{fault!r} is put on no module" in said, said


def test_a_module_code_takes_its_module(tmp_path: Path, rig: Rig) -> None:
    fault = _check(tmp_path, rig, "module = 3", "fastcat:inject:module:0x0B")
    assert [c.target for c in fault.inject] == ["fastcat/3"]


def test_the_docs_example_passes_the_start_check(tmp_path: Path, rig: Rig) -> None:
    """The [exercise] example of docs/classroom.md, as an instructor copies it."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "classroom.md").read_text()
    block = text.split("```toml\n[exercise]\n", 1)[1].split("```", 1)[0]
    keys = {line.split("=")[0].strip(): line.split("=")[1].split("#")[0].strip()
            for line in block.splitlines() if "=" in line}
    fault = _check(tmp_path, rig, "\n".join(f"{k} = {v}" for k, v in keys.items()
                                            if k != "fault"), keys["fault"].strip('"'))
    assert fault.module
