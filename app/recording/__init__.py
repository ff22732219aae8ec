"""Rerun recordings of a rig (issue 6): see :mod:`app.recording.recorder` and
docs/recording.md."""

from app.recording.blueprint import rig_blueprint
from app.recording.recorder import RigRecorder, attach_to_runtime, scenario_observer

__all__ = ["RigRecorder", "attach_to_runtime", "rig_blueprint", "scenario_observer"]
