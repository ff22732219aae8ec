"""The master's quiet spans (docs/performance.md "Quiet spans", docs/ethercat-master.md).

A quiet span is a run of the master's *quiet cycles* (still.py) with nothing due in between:
every step a cycle, every slave reachable, present, with an empty mailbox, in the state the
last watch kept and left unserved (at its target, or not due for a retry before the span
ends), no frame to lose, no damaged cable (its draws), no wire master, no hook queued, the
line as last applied, and the DC unit either COMPENSATING without a fault with a window no
narrower than the healthy noise (so that every draw falls in it) or IDLE without DC slaves.
Each of those steps would then do exactly this: pass each slave one frame (its
``skip_frames`` does that for the whole span, the slave having said ``frames_quiet``), count
a frame, draw the healthy deviation once (``DcUnit.compensate``, which resets ``outside``),
and count what it left out. Nothing else
moves: the states, the reach and the slaves' answers stay as they are while every other model
of the rig is quiet too, which the rig checks before it skips.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.ethercat import AlState
from devices.master.dc import NOISE_NS, NOISE_SPAN, DcState
from devices.master.links import RANK

if TYPE_CHECKING:
    from devices.master.master import EtherCatMaster

FAR_US = 1 << 62  # no end of its own: the rig's span decides


class SpanMixin:
    """:meth:`quiet_until` and :meth:`skip_to` of the EtherCAT master."""

    def quiet_until(self: EtherCatMaster, step_us: int) -> int:
        now = self.now_us
        if not self.SKIP_STILL or self.external or self.to_lose or self._bursting \
                or self.damaged or self.hooks.queued:
            return now
        watched = self._watched
        if watched is None or self.cycle_us > step_us or self.next_cycle_us > now + step_us:
            return now
        dc = self.dc
        if dc.state is DcState.COMPENSATING:
            if dc.fault is not None or dc.window_ns < NOISE_NS or not self._dc_links:
                return now
        elif dc.state is not DcState.IDLE or self._dc_links:
            return now
        powered = list(map(getattr, self._slaves, self._power_names, self._power_defaults))
        plugs = list(map(getattr, self._slaves, self._plug_names, self._plug_defaults))
        if powered != self._line_powered or plugs != self._line_plugs \
                or self.cables != self._line_cables:
            return now
        target = self.target
        held = AlState.SAFEOP if self.dc_hold and RANK[target] > RANK[AlState.SAFEOP] \
            else target
        until = FAR_US
        reach = self._line_reach
        for link, p, slave, reachable, _frame, _take, uses_dc, esm_view in self._rows:
            if not (reach[p] and link.present and link.pending is None and reachable()):
                return now
            frames_quiet = getattr(slave, "frames_quiet", None)
            if frames_quiet is None or not frames_quiet():
                return now
            state = slave.esm.state if esm_view else slave.al_state  # type: ignore[attr-defined]
            if state is not link.believed or state is not watched[p]:
                return now
            if state is not (held if uses_dc else target):
                # Not at its target: left alone until its retry is due (startup._serve).
                until = min(until, link.next_try_us - step_us)
                if until <= now:
                    return now
        if until == FAR_US:
            return until
        return now + (until - now) // step_us * step_us

    def frames_promised(self: EtherCatMaster, step_us: int) -> bool:
        """A slave's question (TRS-CAT: its SYNC0s take the frame of the cycle before): will
        the master's quiet steps pass it one frame at every step of a span? They will whenever
        the master is quiet at all (quiet_until: every step a cycle, internal mode, every slave
        reachable and present, nothing to lose) and skip_to passes them on with
        ``skip_frames``; the rig skips only while the master is quiet. Only a cycle longer than
        the step or a wire master make it "no" before the master's own answer."""
        return self.cycle_us <= step_us and not self.external

    def skip_to(self: EtherCatMaster, t_us: int, step_us: int) -> None:
        steps = (t_us - self.now_us) // step_us  # each one a cycle (quiet_until)
        if steps <= 0:
            return
        rows = self._rows
        for _link, _p, slave, *_rest in rows:
            slave.skip_frames(steps, t_us)  # type: ignore[attr-defined]
        if rows:
            self.frames += steps
        skipped = self.skipped
        skipped.line += steps
        skipped.serve += steps * len(rows)  # in a quiet cycle every slave is left unserved
        skipped.watch += steps
        dc = self.dc
        if dc.state is DcState.COMPENSATING:  # DcUnit.compensate once a step, in the window
            below = self.rng._randbelow
            for _ in range(steps - 1):
                below(NOISE_SPAN)
            dc.deviation_ns = below(NOISE_SPAN) - NOISE_NS
            dc.outside = 0
            skipped.dc += steps
        else:  # IDLE without DC slaves: measure() keeps the deviation at 0
            dc.deviation_ns = 0
        self.next_cycle_us = t_us + self.cycle_us
        self.link_up = bool(rows)
        self.now_us = t_us
