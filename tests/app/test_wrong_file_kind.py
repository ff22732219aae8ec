"""A scenario given where a rig file goes (``--rig``), or a rig file where a scenario goes,
is one line that says which kind of file it is and where it belongs. Before, a scenario
given to ``--rig`` read "scenario: unknown key (known here: cpx, fastcat, ...); did you mean
'servo'?", and a rig file given to ``scenario run`` "cpx: unknown key"."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, RigConfigError, load_rig_spec
from app.scenario import ScenarioError, load_scenario

SCENARIO = Path("static/scenarios/cable_pulled.toml")


def test_scenario_as_rig_file_names_the_kind() -> None:
    with pytest.raises(RigConfigError) as caught:
        load_rig_spec(SCENARIO)
    said = str(caught.value)
    assert "a scenario file, not a rig file" in said and "scenario run" in said
    assert "did you mean" not in said and "\n" not in said


def test_rig_file_as_scenario_names_the_kind() -> None:
    with pytest.raises(ScenarioError) as caught:
        load_scenario(DEFAULT_RIG)
    said = str(caught.value)
    assert "a rig file, not a scenario" in said and "--rig" in said
    assert "unknown key" not in said and "\n" not in said
