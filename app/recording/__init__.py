"""Rerun recordings of a rig (issue 6): see :mod:`app.recording.recorder` and
docs/recording.md."""

from app.recording import allocators

allocators.configure()  # before rerun loads: its allocator reads its options then

from app.recording.blueprint import rig_blueprint  # noqa: E402
from app.recording.recorder import RigRecorder, attach_to_runtime, scenario_observer  # noqa: E402

__all__ = ["RigRecorder", "attach_to_runtime", "rig_blueprint", "scenario_observer"]
