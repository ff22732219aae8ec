"""Quiet spans of the TRS-CAT (docs/trscat.md "Quiet spans"; the contract: devices/device.py
``DeviceModel.quiet_until`` and devices/master/links.py ``Slave``).

Three kinds of quiet step, told apart by the state alone (so :meth:`skip_to` needs no record
of what :meth:`quiet_until` answered):

- *off*: without the logic supply a step only moves the clock; a frame does nothing.
- *free*: powered, DC-SYNC not running (power-up detection, INIT, PRE-OP; SAFE-OP / OP in
  FREE-RUN): a quiet step (``_step_in_full`` with ``quiet``) runs the 500 us local cycles
  with every slot still (only ``next_free_us`` and ``skipped_slot_cycles`` move), leaves the
  calm sync state and the alarm causes alone, and refreshes no LED unless LINK-ACT's activity
  flips. What ends the span: the end of the power-up detection, the activity window (50 ms
  after the last frame) and, in OP, the SM watchdog (100 ms after the last SM event) -- each
  only if no frame comes; a frame only moves ``last_frame_us`` (and, in SAFE-OP / OP, the SM
  event time; nothing is written, so the latch copies nothing).
- *sync0*: DC-SYNC running (SAFE-OP / OP), every step the steady step of stepping.py: one
  SYNC0 takes the one frame of the last cycle. Each SYNC0 is a state change that depends on
  a frame having come: without frames the second SYNC0 of the span already counts an SM
  event missed (0x1C32:11) and the fourth raises the sync error, so no span of more than three
  steps holds "whether or not the frames arrive". This kind is taken only when whoever sends
  the frames promised them (``frames_promised``): then the SYNC0s are a counter
  (``next_sync0_us``, ``last_sm_event_us``, ``skipped_slot_cycles``) and nothing ends the span.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, ClassVar

from devices.ethercat import AlState
from devices.trscat.alarms import TrsBus
from devices.trscat.stepping import ACTIVITY_WINDOW_US
from devices.trscat.sync import CALC_COPY_US, FREE_RUN_CYCLE_US, SYNC_ERROR_LIMIT, SyncState
from devices.trscat.transitions import SM_WATCHDOG_US

if TYPE_CHECKING:
    from devices.trscat.esm import Esm
    from devices.trscat.indicators import LedInputs
    from devices.trscat.io import SlotIo
    from devices.trscat.sync import SyncUnit

# "No end": far beyond any request (the rig takes the least of every device's answer).
FAR_STEPS = 1 << 40
_LATCHING = (AlState.SAFEOP, AlState.OP)
_DC_RUNNING, _FREE_RUN, _DETECTING = SyncState.DC_RUNNING, SyncState.FREE_RUN, TrsBus.DETECTING


class SpansMixin:
    """``quiet_until`` / ``skip_to`` / ``frames_quiet`` / ``skip_frames`` of
    :class:`~devices.trscat.device.TrsCat`."""

    # Set by the master that sends this slave its process-data frames (None: nobody does).
    # ``frames_promised(step_us)`` True promises: if the master's own steps are quiet over a
    # span (the rig skips only when they are), they exchange one frame with this slave at
    # every step of it, at the step's time and after this slave's step (internal mode, the
    # master's cycle = step_us, every cable on the way to this slave connected, no frame to
    # lose), and the master's skip_to calls skip_frames(n, T) for them. That is the rule of
    # the contract ("may assume every other model quiet over the span") applied to the master:
    # its quiet steps are what sends the frames.
    frames_promised: Callable[[int], bool] | None = None

    # Provided by TrsCat (declared for type checkers).
    now_us: int
    powered: bool
    link_in: bool
    bus: TrsBus
    detect_done_us: int
    esm: Esm
    sync: SyncUnit
    sync_state: SyncState
    last_sm_event_us: int | None
    last_frame_us: int | None
    rail: list[SlotIo | None]
    _dirty: bool
    _quiet: bool
    _plan: list[tuple[int, SlotIo, bool, float]] | None
    _all_still: bool
    _latched_moved: bool
    _plc_written: bool
    _led_inputs: LedInputs | None
    skipped_slot_cycles: int
    SKIP_STILL: ClassVar[bool]

    def quiet_until(self, step_us: int) -> int:
        now = self.now_us
        if not self.powered:
            return now + FAR_STEPS * step_us  # a step moves the clock, a frame does nothing
        # The next step must be a quiet one that skips every slot (stepping.py): cheap
        # early-outs first, they are what a busy device answers.
        old = self._led_inputs
        if self._dirty or not self._quiet or not self.SKIP_STILL or self._plan is None \
                or not self._all_still or self._latched_moved or old is None:
            return now
        sync = self.sync
        first = now + step_us
        last = self.last_frame_us
        # LINK-ACT's activity at the first step, with or without a frame in between.
        if (last is not None and first - last <= ACTIVITY_WINDOW_US) is not old.activity:
            return now
        promise = self.frames_promised
        framed = promise is not None and self.link_in and promise(step_us)
        if sync.running:
            # sync0: only with the frames promised (module docstring), one SYNC0 per step,
            # each taking the frame of the step before (take_one_sync0), the steady step's
            # every condition holding and staying so (nothing it reads moves but the clock).
            arrivals = sync.arrivals
            lead = sync.next_sync0_us - now  # the first SYNC0 after the last frame
            if not framed or sync.period_us != step_us or not CALC_COPY_US <= lead <= step_us \
                    or len(arrivals) != 1 or arrivals[0] > sync.next_sync0_us - CALC_COPY_US \
                    or sync.sync0_lost or sync.jitter_us or sync.drop_frames \
                    or sync.sm_missed >= SYNC_ERROR_LIMIT \
                    or sync.without_sync0 >= SYNC_ERROR_LIMIT \
                    or self.sync_state is not _DC_RUNNING \
                    or self.esm.state not in _LATCHING or self._plc_written \
                    or not old.activity or step_us > ACTIVITY_WINDOW_US \
                    or self.bus is _DETECTING:
                return now
            return now + FAR_STEPS * step_us
        # free: the sync state must be the calm FREE_RUN (no _check_sync).
        if self.sync_state is not _FREE_RUN:
            return now
        far = now + FAR_STEPS * step_us
        until = far
        if self.bus is _DETECTING:  # the step at or after detect_done_us finishes it
            until = now + (self.detect_done_us - 1 - now) // step_us * step_us
            if until < first:
                return now
        op = self.esm.state is AlState.OP
        if op:  # the SM watchdog of OP (_step_in_full)
            sm = self.last_sm_event_us
            if sm is None or first - sm > SM_WATCHDOG_US:
                return now
        if framed:
            # A frame at every step: activity stays lit (checked at the first step above,
            # and lit it must be, or the first frame would light it), and in OP each frame is
            # an SM event (no output written: _plc_written is False while quiet in OP; none
            # dropped: a dropped frame is no SM event).
            if not old.activity or step_us > ACTIVITY_WINDOW_US or sync.drop_frames or \
                    (self.esm.state in _LATCHING and self._plc_written):
                return now
            return until
        # No frame promised: the span ends before "no frame since" changes a step.
        if old.activity:
            assert last is not None  # activity needs a frame
            until = min(until, now + (last + ACTIVITY_WINDOW_US - now) // step_us * step_us)
        if op:
            sm = self.last_sm_event_us
            assert sm is not None
            until = min(until, now + (sm + SM_WATCHDOG_US - now) // step_us * step_us)
        return until

    def skip_to(self, t_us: int, step_us: int) -> None:
        """As the quiet steps up to ``t_us`` (the kind read off the state, as quiet_until did;
        the frames of a sync0 span are :meth:`skip_frames`')."""
        if t_us == self.now_us:
            return
        if self.powered:
            sync = self.sync
            plan = self._plan
            assert plan is not None, "skip_to without a quiet span"
            if sync.running:  # sync0: take_one_sync0 at every step, the steady step's rest
                period = sync.period_us
                first = sync.next_sync0_us
                n = (t_us - first) // period + 1  # SYNC0s in (now, t_us]: one per step
                sync.next_sync0_us = first + n * period
                sync.arrivals = []
                sync.sync0_seen = True
                sync.sm_missed = 0
                self.last_sm_event_us = first + (n - 1) * period
                self.skipped_slot_cycles += n * len(plan)
            else:  # free: the 500 us local cycles in (now, t_us], every slot skipped
                due = sync.next_free_us
                if due <= t_us:
                    n = (t_us - due) // FREE_RUN_CYCLE_US + 1
                    sync.next_free_us = due + n * FREE_RUN_CYCLE_US
                    self.skipped_slot_cycles += n * len(plan)
            self._dirty = False
        self.now_us = t_us

    # ---- the master's side ----------------------------------------------------------------
    def frames_quiet(self) -> bool:
        """An exchange_frame now, and one per cycle while this slave's steps stay quiet, would
        change nothing but what :meth:`skip_frames` sets."""
        if not (self.powered and self.link_in):
            return True  # exchange_frame returns at once
        sync = self.sync
        old = self._led_inputs
        if sync.drop_frames or old is None or not old.activity:
            return False  # a frame dropped (a counter of its own), or LINK-ACT lights up
        if sync.running:  # the frame waits for SYNC0 (quiet_until checks it is in time)
            return not sync.jitter_us  # a jitter draws from the rng and may come late
        # FREE-RUN: an SM2 event at once; in SAFE-OP / OP it latches, copying nothing unless
        # an output was written since the last latch.
        return not (self._plc_written and self.esm.state in _LATCHING)

    def skip_frames(self, n: int, last_us: int) -> None:
        """As ``n`` frames that :meth:`frames_quiet` allowed, one per cycle, the last at
        ``last_us``, each after this slave's step at its time (after :meth:`skip_to`)."""
        if n <= 0 or not (self.powered and self.link_in):
            return
        self.last_frame_us = last_us
        sync = self.sync
        sync.last_frame_us = last_us
        if sync.running:
            # Each frame came after a step whose SYNC0 took the one before (sync0 span):
            # sync0_seen was True, so it is False now with none without SYNC0, and the
            # frame waits alone for the next SYNC0. No draw: jitter_us is 0.
            sync.sync0_seen = False
            sync.without_sync0 = 0
            sync.arrivals = [last_us]
        elif self.esm.state in _LATCHING:
            self.last_sm_event_us = last_us  # _latch_outputs with nothing written

