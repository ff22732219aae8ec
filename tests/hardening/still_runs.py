"""What the still-step differential tests share: a scenario's rig, and a run of the scenario
that records every event line and what ``capture`` takes at each checkpoint and at the end."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import Scenario, run_scenario, scenario_rig_path


def scenario_rig(scenario: Scenario) -> Rig:
    """The scenario's own rig (the default rig when it names none), flash in memory."""
    rig_path = scenario_rig_path(scenario, None)
    return build_rig(load_rig_spec(Path(rig_path) if rig_path else DEFAULT_RIG), state_dir=None)


def checkpoint_run(scenario: Scenario, rig: Rig,
                   capture: Callable[[Rig], Any] = lambda rig: rig.snapshot()
                   ) -> tuple[list[str], dict[str, Any]]:
    """(the events as JSON lines, {checkpoint text or "end": capture(rig)})."""
    seen: dict[str, Any] = {}

    def on_step(step: Any, rig: Rig) -> None:
        if step.kind == "checkpoint":
            seen[step.text] = capture(rig)

    run = run_scenario(scenario, rig, on_step=on_step)
    seen["end"] = capture(rig)
    return [json.dumps(e.to_record(), sort_keys=True) for e in run.events], seen
