"""When a drive step may be skipped: the step that repeats a still one (docs/performance.md).

A drive standing still (switched off, or holding in torque with its filters settled) does the
same nothing every millisecond. The drive runs a full step, and when that step left every part
of its state exactly as it found it, emitted nothing and read no clock (no boot, save, indirect
access or latch timing under way), the next step of the same length from the same state does
the same: it is skipped until something from outside touches the drive (a command, a register,
parameter or object write, an alarm) or the step length changes.

"Exactly" is checked, not assumed: :func:`state_key` is a value copy of everything a step can
change, compared before and after. It is taken only when the cheap signs of standing still hold
(:func:`may_settle`), so a moving drive pays a few attribute reads for it; and a drive that
looks still but is not (a current filter still decaying, a speed-window timer counting) is
checked less and less often (:class:`StillSteps`: after 1, 2, 4 .. 128 steps), so the check
costs it about 1 % of a step. Checking less often only delays the skipping; it cannot make a
skipped step differ.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devices.servo.ds402 import State
from devices.stillness import Backoff, slot_names
from devices.stillness import value_key as _value

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

# Attributes no step writes (identity, wiring of the model, the dictionary whose writes touch
# the drive), the skipping's own bookkeeping, or caches of pure functions of the state (the
# step cost work, ticking.py: what they hold never changes what a step does); everything else
# is in the key.
NOT_STATE = frozenset({
    "device_id", "rng", "now_us", "events", "config", "flash", "geometry", "od", "indirect",
    "_t_us", "_touched", "_still", "SKIP_STILL", "_levels_cache", "_quiet_evaluation",
    "_lag_cache", "_cruise", "meter",
    "regs", "params", "wired", "_levels", "latched_at_power_up",  # in the key, as flat dicts
})
FLAT = ("regs", "params", "wired", "_levels", "latched_at_power_up")  # str/int -> int/bool


def state_key(drive: ServoDrive) -> tuple[Any, ...]:
    """Everything a drive step can change, by value (the indirect access by its values). The
    current meter comes last: ``key[:-1]`` is everything but the meter (quiet spans,
    :func:`filter_only`)."""
    own = tuple((k, _value(v)) for k, v in vars(drive).items() if k not in NOT_STATE)
    flat = tuple(tuple(getattr(drive, name).items()) for name in FLAT)
    indirect = drive.indirect
    return own, flat, tuple(indirect.values.items()), len(indirect._jobs), \
        tuple(getattr(drive.meter, name) for name in slot_names(type(drive.meter)))


def filter_only(before: tuple[Any, ...], after: tuple[Any, ...]) -> bool:
    """Two :func:`state_key` values that differ at most in the current meter (its RMS filter
    settling: nothing in a step reads the meter but the meter itself)."""
    return before[:-1] == after[:-1]


class StillSteps(Backoff):
    """The drive's bookkeeping: the last step's length if it changed nothing (else None), the
    alarm bank it saw and its change count, and when to check again after a failed check
    (devices/stillness.py's 1, 2, 4 .. 128 backoff).

    ``filter_dt``: the step length at which the last checked step changed nothing but the
    current meter's filter (None if it changed more, or the drive was touched, or the alarm
    bank or the step length changed since): every step of that length from then on does the
    same, so the drive is quiet and a quiet span moves only the filter (drive.py,
    :meth:`~devices.servo.drive.ServoDrive.quiet_until`)."""

    __slots__ = ("alarms", "changes", "dt", "filter_dt")

    def __init__(self) -> None:
        super().__init__()
        self.dt: int | None = None
        self.filter_dt: int | None = None
        self.alarms: object = None
        self.changes = 0


def may_settle(drive: ServoDrive) -> bool:
    """The cheap signs of a step that reads no clock and moves nothing."""
    plant, trajectory = drive.plant, drive.trajectory
    return (plant.omega == 0.0 and trajectory.velocity == 0.0 and trajectory.idle
            and drive.saving_until is None and drive.save_pending is None
            and drive.latch.rose_at_us is None and not drive.indirect._jobs
            and not (drive.powered and drive.state is State.NOT_READY_TO_SWITCH_ON))
