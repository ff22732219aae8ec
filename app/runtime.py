"""The live runtime: one simulation thread owns the rig; everyone else talks to it by message.

viser callbacks, protocol servers and the CLI never touch a model. They call
:meth:`Runtime.command` (a named device action) or :meth:`Runtime.submit` (any function that
needs the models) and get a ``concurrent.futures.Future``; the simulation thread runs queued
work at step boundaries, in arrival order. A protocol server that answers each request at once
(the Modbus line) uses :meth:`Runtime.call` instead: the function runs in the caller's thread
while the simulation thread is between two steps (it holds the rig lock while it steps), which
spares the request two thread hand-overs (benchmark 4, docs/hardening.md). Either way the
models are only ever touched by one thread at a time. Views read the latest :class:`Frame`
and the bounded event journal; both are published by the simulation thread.
"""

from __future__ import annotations

import collections
import itertools
import logging
import queue
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, TypeVar

from app.modbus.line import ServedLine
from app.rig import ObserverSpan, Rig
from devices.events import Event

logger = logging.getLogger(__name__)

T = TypeVar("T")

MAX_CATCH_UP_US = 200_000  # beyond this lag the clock slips instead of racing to catch up
# The simulation thread naps 1 ms between wake-ups while something talks to the rig (queued
# work within ACTIVE_S, or a real-time step listener: the EtherCAT wire), so an answer due at
# the next step goes out within about a millisecond. Otherwise it naps IDLE_NAP_S and steps the
# elapsed milliseconds in one go: the simulated time is the same, but a wake-up costs about
# 50 us of CPU on these machines, more than an idle default-rig step (docs/performance.md,
# "Served rigs"). Queued work wakes the thread at once either way.
ACTIVE_NAP_S = 0.001
IDLE_NAP_S = 0.010
ACTIVE_S = 0.5
JOURNAL_LENGTH = 20_000


def nap_s(now: float, last_work: float, next_publish: float, realtime: bool) -> float:
    """How long the simulation thread sleeps before it looks again (monotonic seconds)."""
    if realtime or now - last_work <= ACTIVE_S:
        return ACTIVE_NAP_S
    return min(IDLE_NAP_S, max(ACTIVE_NAP_S, next_publish - now))


@dataclass(frozen=True)
class Frame:
    """What views read: the rig's state at one simulated instant."""

    seq: int
    t_us: int
    snapshot: dict[str, Any]


MAX_SPEED = 1000.0  # simulated seconds per wall second: far above what a CPU gives (Runtime.run)


class Runtime:
    def __init__(self, rig: Rig, speed: float = 1.0, publish_hz: float = 30.0) -> None:
        self.rig = rig
        self._speed = speed
        self._rebase = False
        self._paused = False
        self._publish_period = 1.0 / publish_hz
        # (work, its future, whether it may write to the models: Rig.touch before it runs)
        self._work: queue.Queue[tuple[Callable[[], Any], Future[Any], bool]] = queue.Queue()
        self._lock = threading.Lock()  # the journal and the frame
        # The rig: held by the simulation thread for each step (and the work and publication
        # around it) and by call(); re-entrant, as queued work may publish or call.
        self._rig_lock = threading.RLock()
        self._sim_waiting = False  # the simulation thread wants the rig lock: call() waits
        self._caller: int | None = None  # the thread inside call(), if any
        # The last events; their sequence numbers are consecutive and end at _event_seq, so
        # none is stored (a (seq, event) tuple and its int were ~90 bytes an event: issue 7).
        self._journal: collections.deque[Event] = collections.deque(maxlen=JOURNAL_LENGTH)
        self._event_seq = 0
        self._frame = Frame(0, rig.clock.now_us, rig.snapshot())
        self._frame_revision = rig.revision  # the rig's revision when the frame was taken
        self._stop = threading.Event()
        self._wake = threading.Event()  # set by submit(): queued work runs without a nap
        self._thread: threading.Thread | None = None
        self._listeners: list[Callable[[list[Event]], None]] = []
        self._step_listeners: list[Callable[[int], None]] = []
        self._frame_listeners: list[Callable[[Frame], None]] = []
        self._publish_soon = False  # a command ran: publish at once, not at the next 1/30 s
        self._realtime_listeners = 0  # step listeners that need each step within ~1 ms
        self._unspanned_listeners = 0  # step listeners that need every step (no quiet spans)
        self._listener_spans: list[ObserverSpan] = []
        self._worked = False  # _drain_work ran something since the loop last looked
        # The drives' Modbus line as served (framing, port), once its server listens; None
        # while none does (a scenario run, a rig without drives). The Drive tab reads it.
        self.modbus: ServedLine | None = None

    # ---- control -------------------------------------------------------------------------
    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="fieldrig-sim", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout=5)

    @property
    def speed(self) -> float:
        return self._speed

    def set_speed(self, speed: float) -> None:
        if not 0 < speed <= MAX_SPEED:
            raise ValueError(f"speed must be in (0, {MAX_SPEED:g}], got {speed}")
        self._speed = speed
        self._rebase = True  # the new speed counts from now, not from the start

    @property
    def paused(self) -> bool:
        return self._paused

    def set_paused(self, paused: bool) -> None:
        self._paused = paused

    # ---- messages to the simulation thread -----------------------------------------------
    def submit(self, fn: Callable[[], T]) -> Future[T]:
        """Run ``fn`` in the simulation thread at the next step boundary."""
        return self._queue(fn, writes=True)

    def _queue(self, fn: Callable[[], T], writes: bool) -> Future[T]:
        fut: Future[T] = Future()
        self._work.put((fn, fut, writes))
        self._wake.set()
        return fut

    def call(self, fn: Callable[[], T]) -> T:
        """Run ``fn`` now, in the calling thread, between two steps of the simulation thread
        (waiting for the step in progress, if any), and journal the events it caused. For a
        protocol server that answers a request as soon as it is framed; it must be quick (the
        simulation waits for it) and must not wait on the simulation thread itself."""
        # Python's locks are not fair: a caller in a tight loop could take the lock again and
        # again while the simulation thread, woken, waits for the GIL. Waiting for its turn
        # here (sleep(0) hands the GIL over) keeps the clock running under any request rate.
        # (A call made from inside a call holds the lock already: it must not wait.)
        me = threading.get_ident()
        while self._sim_waiting and self._caller != me:
            time.sleep(0)
        with self._rig_lock:
            outer, self._caller = self._caller, me
            self.rig.touch()  # a protocol server's request may write to a device
            # A request talks to the rig as queued work does: the thread keeps 1 ms naps, so
            # the next request reads the rig within a step of wall time, not 10 ms behind.
            self._worked = True
            try:
                return fn()
            finally:  # what it emitted before failing is journalled too, as submit does
                self._caller = outer
                self._journal_events(self.rig.take_events())

    def command(self, target: str, action: str, args: dict[str, Any] | None = None) -> Future[Any]:
        """Apply a device action; the future holds its result or its CommandError/SdoAbort.

        The frame after a command is published as soon as it ran (a click shows without
        waiting for the next 1/30 s publication; benchmark 2, docs/performance.md)."""
        def run() -> Any:
            self._publish_soon = True
            return self.rig.apply(target, action, dict(args or {}))
        return self.submit(run)

    def power_on(self) -> list[Future[Any]]:
        """Switch on every device with a power action, as a rig on a bench starts when its
        supply is switched on (a served rig, the benchmarks); the commands' futures."""
        return [self.command(device_id, "power", {"on": True})
                for device_id, info in self.rig.describe().items()
                if "power" in info["actions"]]

    def add_listener(self, fn: Callable[[list[Event]], None]) -> None:
        """``fn(events)`` runs after each batch, with the rig held (in the simulation thread,
        or in the thread of a :meth:`call`); keep it quick."""
        self._listeners.append(fn)

    def add_frame_listener(self, fn: Callable[[Frame], None]) -> None:
        """``fn(frame)`` runs in the simulation thread after each publication (a view can wake
        up on it instead of polling); keep it very quick."""
        self._frame_listeners.append(fn)

    def add_step_listener(self, fn: Callable[[int], None], realtime: bool = False,
                          quiet_until: ObserverSpan | None = None) -> None:
        """``fn(now_us)`` runs in the simulation thread after every step; keep it very quick.
        ``realtime``: the listener needs each step close to its wall time (it relates steps
        to wall-clock arrivals), so the thread never steps in idle batches while it is there.
        ``quiet_until(now_us, step_us)``: the time up to which ``fn`` would do nothing after
        the steps of a quiet rig; with it the rig may skip quiet spans (Rig.quiet_steps) and
        ``fn`` is not called for their steps. A listener without it keeps the rig stepping one
        step at a time."""
        self._step_listeners.append(fn)
        self._realtime_listeners += realtime
        if quiet_until is None:
            self._unspanned_listeners += 1
        else:
            self._listener_spans.append(quiet_until)

    # ---- what views read ------------------------------------------------------------------
    @property
    def frame(self) -> Frame:
        with self._lock:
            return self._frame

    def events_since(self, seq: int) -> tuple[int, list[Event]]:
        """Events journalled after ``seq`` and the sequence number to ask from next time."""
        with self._lock:
            new = min(max(self._event_seq - seq, 0), len(self._journal))
            # From the right end: the cost grows with the new events only.
            newer = list(itertools.islice(reversed(self._journal), new))
            newer.reverse()
            return self._event_seq, newer

    @property
    def journal_seq(self) -> int:
        """The sequence number of the last event journalled (what ``events_since`` returns)."""
        with self._lock:
            return self._event_seq

    def journal(self, events: list[Event]) -> None:
        """Add events that did not come from a model (captions of a scenario played live)."""
        self.submit(lambda: self._journal_events(list(events)))

    def advance(self, duration_us: int) -> Future[None]:
        """Step the rig by ``duration_us`` now, in the simulation thread (for a paused rig:
        tests and screenshot tooling step it to an exact instant, then read the frame)."""
        def run() -> None:
            end = self.rig.clock.now_us + duration_us
            while self.rig.clock.now_us + self.rig.clock.step_us <= end:
                self._step_or_skip(end)
            self._publish()
        return self._queue(run, writes=False)  # it only steps: no touch

    # ---- the simulation thread ------------------------------------------------------------
    def _run(self) -> None:
        wall0 = time.monotonic()
        sim0 = self.rig.clock.now_us
        next_publish = 0.0
        last_work = wall0
        while not self._stop.is_set():
            self._sim_waiting = True
            with self._rig_lock:
                self._sim_waiting = False
                self._journal_events(self._drain_work())
            now = time.monotonic()
            if self._rebase:
                self._rebase = False
                wall0, sim0 = now, self.rig.clock.now_us
            if self._paused:
                wall0, sim0 = now, self.rig.clock.now_us
            else:
                target = sim0 + int((now - wall0) * 1e6 * self._speed)
                if target - self.rig.clock.now_us > MAX_CATCH_UP_US:
                    # Too far behind (a slow machine, a speed the CPU cannot give): run at
                    # most MAX_CATCH_UP_US now and let the clock slip for the rest.
                    target = self.rig.clock.now_us + MAX_CATCH_UP_US
                    sim0, wall0 = target, now
                while self.rig.clock.now_us + self.rig.clock.step_us <= target:
                    # Each step's events reach the listeners before the step listeners run,
                    # so an observer never sees a sample ahead of the events that led to it.
                    # The lock is taken per step: a call() waits for one step at most.
                    self._sim_waiting = True
                    with self._rig_lock:
                        self._sim_waiting = False
                        self._step_or_skip(target)
                        self._journal_events(self._drain_work())
                    if self._paused or self._rebase:
                        # The work just taken paused the rig or moved its clock (a scenario
                        # load resets it to 0): ``target`` belongs to the old clock. Going on
                        # ran a fresh rig at CPU speed up to the old time ("finished · t =
                        # 0.0 s", then "t = 756.8 s of 16 s"); the next round starts afresh.
                        break
            if now >= next_publish or self._publish_soon:
                self._sim_waiting = True
                with self._rig_lock:
                    self._sim_waiting = False
                    self._publish()
                self._publish_soon = False
                if now >= next_publish:
                    next_publish = now + self._publish_period
            if self._worked:
                self._worked, last_work = False, now
            self._wake.wait(nap_s(now, last_work, next_publish, bool(self._realtime_listeners)))
            self._wake.clear()

    def _step_or_skip(self, end_us: int) -> None:
        """One step, or a quiet span up to ``end_us`` at most (docs/performance.md "Quiet
        spans"): skipped steps emit nothing and need no listener, but for the last one of a
        span that ends where a listener is due (Rig.quiet_span), after which they all run."""
        rig = self.rig
        if not self._unspanned_listeners:
            span, observed = rig.quiet_span((end_us - rig.clock.now_us) // rig.clock.step_us,
                                            self._listener_spans)
            if span:
                rig.skip(span)
                if observed:  # a listener is due at the span's last step: as after a step
                    for fn in self._step_listeners:
                        fn(rig.clock.now_us)
                return
        self._journal_events(rig.step())
        for fn in self._step_listeners:
            fn(rig.clock.now_us)
        if self._unspanned_listeners:
            rig.touch()  # such a listener (the wire bridge) may write to the models each step

    def _drain_work(self) -> list[Event]:
        events: list[Event] = []
        while True:
            try:
                fn, fut, writes = self._work.get_nowait()
            except queue.Empty:
                return events
            if not fut.set_running_or_notify_cancel():
                continue
            self._worked = True
            if writes:
                self.rig.touch()  # work may write to a device directly (an adapter's request)
            try:
                fut.set_result(fn())
            except Exception as exc:  # delivered to the caller, never kills the simulation
                fut.set_exception(exc)
            events.extend(self.rig.take_events())

    def _journal_events(self, events: list[Event]) -> None:
        if not events:
            return
        with self._lock:
            self._journal.extend(events)
            self._event_seq += len(events)
        for fn in self._listeners:
            try:
                fn(events)
            except Exception:
                logger.exception("event listener failed")

    def _publish(self) -> None:
        rig = self.rig
        # Nothing moved since the last frame but counters: the models that show none keep
        # their snapshot objects (a view may compare them by identity).
        kept = self._frame.snapshot if self._frame_revision == rig.revision else None
        snap = rig.snapshot(kept)
        self._frame_revision = rig.revision
        with self._lock:
            self._frame = frame = Frame(self._frame.seq + 1, self.rig.clock.now_us, snap)
        for fn in self._frame_listeners:
            try:
                fn(frame)
            except Exception:
                logger.exception("frame listener failed")
