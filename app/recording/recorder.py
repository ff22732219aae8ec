"""Record a rig to a Rerun file: events as text logs, states as lanes, signals as scalars.

Everything is on the timeline ``sim_time`` (a duration: simulated time since the rig started),
never on the wall clock, so a recording of a scenario is the same however fast it ran.

Recording must not slow the simulation (issue 6). Nothing is sent per simulation step: the
recorder buffers rows in memory and sends an entity's rows as one column batch (``send_columns``,
~40 us per call whatever its length) when they fill a chunk (``chunk_rows``), everything every
``flush_period_us`` of simulated time, and the fullest entities whenever ``max_buffered_rows``
rows wait in all. Each batch is a chunk of the file, and rerun keeps ~1 KB per chunk in memory
until the footer is written (issue 7): few, long chunks. Snapshots are sampled every
``sample_period_us`` of simulated time, not every 1 ms step; events are recorded with their
own time stamps, so a state or LED change is exact even between samples. See
docs/recording.md.
"""

from __future__ import annotations

import logging
import threading
from array import array
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import rerun as rr

from app.recording import allocators, event_text
from app.recording.blueprint import TIMELINE, lane_style, rig_blueprint, series_style
from app.recording.signals import SeriesInfo, Signal, device_signals, main_machine, state_values
from devices.events import Event
from devices.leds import LedPattern, is_lit

if TYPE_CHECKING:
    from app.rig import Rig
    from app.runtime import Runtime

logger = logging.getLogger(__name__)

DEFAULT_SAMPLE_PERIOD_US = 10_000  # 100 Hz: 5 samples per half period of a flickering LED
# Each send is one chunk: ~2 KB of header in the file, and ~1 KB of rerun's memory until the
# file's footer is written at close (its manifest of every chunk: docs/recording.md).
DEFAULT_FLUSH_PERIOD_US = 300_000_000  # what quiet entities risk losing to a SIGKILL
DEFAULT_CHUNK_ROWS = 4_096  # an entity sampled at every 10 ms fills one in ~41 s
DEFAULT_MAX_BUFFERED_ROWS = 20_000  # ~2.5 MB of rows at most in the buffers


@dataclass
class _Column:
    """Rows of one entity waiting to be sent: times (us) and one value per row.

    Rows wait minutes (a chunk or a period), up to ``max_buffered_rows`` of them: times, and a
    scalar entity's values (``width`` per row, flat), are machine numbers, 8 bytes each; as
    Python ints and tuples of floats a row was ~100 bytes (issue 7 soak, docs/recording.md)."""

    times: array[int] = field(default_factory=lambda: array("q"))
    values: Any = field(default_factory=list)  # texts, lane states; array("d") for scalars
    levels: list[str] = field(default_factory=list)  # text logs only
    width: int = 0  # scalars only: series per row
    info: SeriesInfo | None = None  # scalars only: the series (style) the entity was given
    last: Any = None  # scalars only: the last row kept
    held_us: int | None = None  # scalars only: time of the last sample equal to ``last``

    @classmethod
    def scalars(cls, width: int) -> _Column:
        return cls(values=array("d"), width=width)

    def add_sample(self, t_us: int, row: tuple[float, ...]) -> bool:
        """Keep a sample only when it differs from the last one kept; before it, keep the
        last equal sample too, so a plot holds the old value up to the change instead of
        ramping across the gap. Returns whether a row was added."""
        if row == self.last:
            self.held_us = t_us
            return False
        self.hold()
        self.times.append(t_us)
        self.values.extend(row)
        self.last = row
        return True

    def hold(self) -> None:
        """Keep the pending equal sample (at a change, a flush, the end)."""
        if self.held_us is not None:
            self.times.append(self.held_us)
            self.values.extend(self.last)
            self.held_us = None

    def take(self) -> tuple[np.ndarray, Any, list[str]]:
        times = np.array(self.times, dtype=np.int64).astype("timedelta64[us]")
        out = times, self.values, self.levels
        self.times, self.levels = array("q"), []
        self.values = array("d") if isinstance(self.values, array) else []
        return out


class RigRecorder:
    """One Rerun recording of one rig, written to ``path`` (a ``.rrd`` file).

    Thread-safe: the simulation thread calls :meth:`observe`; any thread may call
    :meth:`flush` (e.g. a download button) or :meth:`close`.
    """

    def __init__(self, path: str | Path, application_id: str = "fieldrig",
                 recording_id: str | None = None, *,
                 sample_period_us: int = DEFAULT_SAMPLE_PERIOD_US,
                 flush_period_us: int = DEFAULT_FLUSH_PERIOD_US,
                 chunk_rows: int = DEFAULT_CHUNK_ROWS,
                 max_buffered_rows: int = DEFAULT_MAX_BUFFERED_ROWS,
                 blueprint: bool = True, start_time: bool = True) -> None:
        if min(sample_period_us, flush_period_us, chunk_rows, max_buffered_rows) <= 0:
            raise ValueError("sample period, flush period, chunk and buffer sizes must be "
                             "positive")
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.sample_period_us = sample_period_us
        self.flush_period_us = flush_period_us
        self.chunk_rows = chunk_rows
        self.max_buffered_rows = max_buffered_rows
        allocators.use_system_pool()  # the sends' columns: see allocators.py
        # rerun's default properties are the wall-clock instant the stream was made
        # (RecordingInfo start_time): a scenario run's file is the same on every run without.
        self._rec = rr.RecordingStream(application_id, recording_id=recording_id,
                                       send_properties=start_time)
        self._rec.set_sinks(rr.FileSink(str(self.path)))
        self._lock = threading.Lock()
        self._scalars: dict[str, _Column] = {}
        self._texts: dict[str, _Column] = {}
        self._lanes: dict[str, _Column] = {}
        self._lane_now: dict[str, str] = {}  # last value sent or buffered per lane
        # Each device's main-machine lane as its snapshots show it (signals.main_machine).
        self._main: dict[str, str] = {}
        self._buffered = 0  # rows waiting in all buffers (at least: a hold adds one more)
        # No entity can hold chunk_rows rows, nor all of them max_buffered_rows, before
        # _buffered reaches this: below it, a flush check costs one comparison.
        self._check_at = min(chunk_rows, max_buffered_rows)
        self._next_sample_us: int | None = None  # None: sample at the first chance
        self._last_flush_us = 0
        self._send_blueprint = blueprint
        self._named = False
        self._closed = False
        self._offset_us = 0  # added to rig times: a restarted rig continues the timeline
        self._last_t_us = 0  # the latest rig time observed
        # The rig's load count (Rig.loads, set by attach_to_runtime / scenario_observer) and
        # its value at the last observation (None: none yet). A change is a new run.
        self.load_count: Callable[[], int] | None = None
        self._load: int | None = None
        # What the last sample gave each scalar column: its row, or the LED pattern its
        # lit / dark row is computed from at each time (resample); None: no sample to repeat.
        self._repeat: list[tuple[_Column, tuple[float, ...], LedPattern | None]] | None = None
        self.runs = 1  # how many times the rig clock started from the beginning, plus one
        # The rig's own reading of AL status codes (event_text.al_status_reader), set by
        # attach_to_runtime / scenario_observer; None: the ETG text only.
        self.al_status: event_text.AlStatusReader | None = None
        # The scenario played on the rig ("" none: Rig.scenario), set with al_status.
        self.scenario_of: Callable[[], str] | None = None

    # ---- what the simulation side calls ----------------------------------------------------
    def quiet_until(self, now_us: int, step_us: int) -> int:
        """Up to when no sample is due (a quiet rig's steps before then need no snapshot).
        None after a load: the next step's observation starts the new run (``_restart``) and
        its sample grid."""
        due = self._next_sample_us
        if due is None or self._loaded():
            return now_us
        return max(now_us, due - 1)

    def sample_due(self, t_us: int) -> bool:
        """Whether a snapshot taken at ``t_us`` would be recorded (take one only then); after
        a load, the new run's first observation is (its full first sample)."""
        return self._next_sample_us is None or t_us >= self._next_sample_us or self._loaded()

    def observe(self, t_us: int, snapshot: Mapping[str, Any] | None,
                events: Iterable[Event]) -> None:
        """Record ``events`` (each at its own time) and, if given, the rig ``snapshot``
        (:meth:`app.rig.Rig.snapshot`) as a sample at ``t_us``."""
        with self._lock:
            if self._closed:
                return
            if self._loaded():
                self._restart(t_us)
            if self.load_count is not None:
                self._load = self.load_count()
            self._last_t_us = t_us
            if snapshot is not None:
                self._learn_machines(snapshot)
            for event in events:
                self._event(event)
            if snapshot is not None:
                self._sample(t_us, snapshot)
            self._flush_due(t_us)

    def resample(self, t_us: int) -> bool:
        """Record at ``t_us`` the sample :meth:`observe` would record for a snapshot equal to
        the last one sampled (a rig whose revision has not moved: app.rig.Rig.revision), without
        taking one: every signal as it was, each LED lit or dark by its pattern at ``t_us``.
        False (nothing recorded) when there is no sample to repeat or a load started a new run
        (the next observation starts it)."""
        with self._lock:
            if self._closed:
                return True
            if self._repeat is None or self._loaded():
                return False
            self._last_t_us = t_us
            at = t_us + self._offset_us
            for column, row, pattern in self._repeat:
                if pattern is not None:
                    row = (1.0 if is_lit(pattern, t_us) else 0.0,)
                if column.add_sample(at, row):
                    self._buffered += 1
            # The state lanes need nothing: the last sample set them, and an event since
            # would have moved the revision.
            self._next_sample_us = (t_us // self.sample_period_us + 1) * self.sample_period_us
            self._flush_due(t_us)
            return True

    def _flush_due(self, t_us: int) -> None:
        if t_us - self._last_flush_us >= self.flush_period_us:
            self._send_buffers()
            self._last_flush_us = t_us
            # A period's rows went out at once: without this, the allocators keep that peak
            # (glibc's part; rerun's and pyarrow's: allocators.configure). Issue 7, the soak.
            # Also after a full chunk's send (_send_full): at most one trim per sending.
            allocators.release_freed()
        elif self._buffered >= self._check_at:
            self._send_full()

    def _loaded(self) -> bool:
        """Whether a scenario load happened since the last observation.
        A load, not the clock going back, starts a new run: a load at 0 s (right after start,
        or twice in a row) puts no clock back, and nothing else does."""
        if self.load_count is None or self._load is None:
            return False
        return self.load_count() != self._load

    # ---- what owners call ------------------------------------------------------------------
    def flush(self, timeout_s: float = 10.0) -> None:
        """Send everything buffered and wait until it is in the file."""
        with self._lock:
            if self._closed:
                return
            self._send_buffers(hold=True)
        self._rec.flush(timeout_sec=timeout_s)

    def buffered_rows(self) -> int:
        """Rows waiting in the buffers, not yet sent to the file."""
        with self._lock:
            return sum(len(c.times) for _send, _path, c in self._columns())

    def recording_bytes(self) -> bytes:
        """The recording so far, as a file the viewer opens (for a download button)."""
        self.flush()
        return self.path.read_bytes()

    def close(self) -> None:
        """Send what is buffered, finish the file (with its footer) and stop recording."""
        with self._lock:
            if self._closed:
                return
            self._send_buffers(hold=True)
            self._closed = True
        self._rec.flush()
        self._rec.disconnect()
        logger.info("recording written to %s", self.path)

    def __enter__(self) -> RigRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- buffering ---------------------------------------------------------------------------
    def _restart(self, t_us: int) -> None:
        """A scenario loaded (Rig.loads moved: the rig restarted factory-fresh, its clock
        at ``t_us``, 0 s). The new run goes on the same timeline after the last one, one
        sample period apart, and starts with a full sample, as the first run did
        (docs/recording.md)."""
        self._send_buffers(hold=True)
        self._offset_us += self._last_t_us - t_us + self.sample_period_us
        self.runs += 1
        self._lane_now.clear()
        for column in self._scalars.values():
            column.last, column.held_us = None, None
        self._next_sample_us = None
        self._repeat = None  # the columns' last rows are gone
        self._last_flush_us = t_us
        at = t_us + self._offset_us
        column = self._texts.setdefault(event_text.RIG_LOG, _Column())
        column.times.append(at)
        column.values.append(f"run {self.runs}: the rig restarted (rig time 0 s is "
                             f"{at / 1e6:g} s of this recording)"
                             + (f": scenario '{self._scenario()}'" if self._scenario() else ""))
        column.levels.append("INFO")
        self._buffered += 1

    def _scenario(self) -> str:
        """The scenario played on the rig ("" none)."""
        return self.scenario_of() if self.scenario_of is not None else ""

    def _session_row(self, at: int, text: str) -> None:
        column = self._texts.setdefault(event_text.RIG_LOG, _Column())
        column.times.append(at)
        column.values.append(text)
        column.levels.append("INFO")
        self._buffered += 1

    def _event(self, event: Event) -> None:
        record = event.to_record()
        column = self._texts.setdefault(event_text.log_path(event), _Column())
        column.times.append(event.t_us + self._offset_us)
        column.values.append(event_text.text(event, record, self.al_status))
        column.levels.append(event_text.level(event, record))
        self._buffered += 1
        lane = event_text.lane_change(event, record, self._main.get(event.device, ""))
        if lane is not None:
            self._lane(lane[0], event.t_us + self._offset_us, lane[1], exact=True)

    def _learn_machines(self, snapshot: Mapping[str, Any]) -> None:
        for device_id, snap in (snapshot.get("devices") or {}).items():
            if device_id not in self._main and isinstance(snap, Mapping):
                machine = main_machine(snap)
                if machine is not None:
                    self._main[device_id] = machine

    def _lane(self, path: str, t_us: int, value: str, exact: bool = False) -> None:
        """A lane keeps changes only. Events (``exact``) carry the time of the change; samples
        catch the initial state and anything no event reported. When a live runtime hands
        over a batch's events after a sample already showed the change, the buffered row
        moves back to the event's time."""
        if self._lane_now.get(path) == value:
            if exact:
                column = self._lanes[path]
                if column.times and column.values[-1] == value and t_us < column.times[-1]:
                    column.times[-1] = t_us
            return
        if path not in self._lane_now:
            style = lane_style(path)
            if style is not None:
                self._rec.log(path, style, static=True)
        self._lane_now[path] = value
        column = self._lanes.setdefault(path, _Column())
        column.times.append(t_us)
        column.values.append(value)
        self._buffered += 1

    def _sample(self, t_us: int, snapshot: Mapping[str, Any]) -> None:
        if not self._named:
            self._start(snapshot, t_us)
        at = t_us + self._offset_us
        devices = snapshot.get("devices") or {}
        for device_id, snap in devices.items():
            for path, value in state_values(device_id, snap):
                self._lane(path, at, value)
        # ~130 signals a sample on the default rig: the usual case (a known entity, its style
        # and width as last time) is one lookup and two checks here; _scalar does the rest.
        scalars = self._scalars
        repeat = []
        buffered = 0
        for device_id, snap in devices.items():
            for signal in device_signals(device_id, snap, t_us):
                values = signal.values
                column = scalars.get(signal.path)
                if column is None or column.info is not signal.info \
                        or column.width != len(values):
                    column = self._scalar(signal)
                if values == column.last:  # add_sample's usual case, without the call
                    column.held_us = at
                else:
                    buffered += column.add_sample(at, values)
                repeat.append((column, values, signal.pattern))
        self._buffered += buffered
        self._repeat = repeat
        period = self.sample_period_us
        self._next_sample_us = (t_us // period + 1) * period  # stay on a regular grid

    def _start(self, snapshot: Mapping[str, Any], t_us: int) -> None:
        self._named = True
        scenario = self._scenario()  # a handed-over file says which demo it is
        if snapshot.get("rig"):
            self._rec.send_recording_name(str(snapshot["rig"])
                                          + (f" · {scenario}" if scenario else ""))
        if scenario:
            self._session_row(t_us + self._offset_us, f"run {self.runs}: scenario '{scenario}'")
        if self._send_blueprint:
            self._rec.send_blueprint(rig_blueprint(snapshot, t_us))

    def _scalar(self, signal: Signal) -> _Column:
        """The column of a new entity, or of one whose width or series changed."""
        column = self._scalars.get(signal.path)
        if column is None:
            column = self._scalars[signal.path] = _Column.scalars(len(signal.values))
        elif column.width != len(signal.values):
            # The module behind this entity changed (another type plugged): the rows sent
            # so far keep their width; a new column starts with the new one.
            self._send_scalars(signal.path, column)
            column.width, column.last, column.held_us = len(signal.values), None, None
        if column.info != signal.info:  # signals caches them: usually the very same object
            self._rec.log(signal.path, series_style(signal), static=True)
        column.info = signal.info
        return column

    # ---- sending -----------------------------------------------------------------------------
    def _send_scalars(self, path: str, column: _Column, hold: bool = False) -> None:
        if hold:
            column.hold()  # the plot reaches this instant, not only the last change
        if not column.times:
            return
        times, rows, _ = column.take()
        values = np.frombuffer(rows, dtype=np.float64).reshape(len(times), column.width)
        self._rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=times)],
                               columns=rr.Scalars.columns(scalars=values))

    def _send_texts(self, path: str, column: _Column, hold: bool = False) -> None:
        if column.times:
            times, texts, levels = column.take()
            self._rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=times)],
                                   columns=rr.TextLog.columns(text=texts, level=levels))

    def _send_lane(self, path: str, column: _Column, hold: bool = False) -> None:
        if column.times:
            times, states, _ = column.take()
            self._rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=times)],
                                   columns=rr.StateChange.columns(state=states))

    def _columns(self) -> Iterator[tuple[Callable[[str, _Column, bool], None], str, _Column]]:
        """Every buffer, with the method that sends it."""
        for send, columns in ((self._send_scalars, self._scalars),
                              (self._send_texts, self._texts), (self._send_lane, self._lanes)):
            for path, column in columns.items():
                yield send, path, column

    def _send_buffers(self, hold: bool = False) -> None:
        """Send every buffered row, one ``send_columns`` per entity that has rows. ``hold``
        also sends each signal's pending unchanged sample (at an explicit flush and at the
        end); periodic flushes leave it pending so a quiet signal costs nothing."""
        for send, path, column in self._columns():
            send(path, column, hold)
        self._buffered = 0
        self._check_at = min(self.chunk_rows, self.max_buffered_rows)

    def _send_full(self) -> None:
        """Send each entity that holds a chunk's worth of rows, as one chunk; then, if all of
        them together still hold ``max_buffered_rows``, the fullest ones until half that is
        left. The others wait for the period: a quiet entity is one chunk per period, not one
        per flush of a busy one."""
        columns = sorted(self._columns(), key=lambda e: len(e[2].times), reverse=True)
        buffered = sum(len(c.times) for _send, _path, c in columns)
        keep = self.max_buffered_rows // 2 if buffered >= self.max_buffered_rows else buffered
        fullest = 0  # rows of the fullest entity left
        sent = False
        for send, path, column in columns:
            rows = len(column.times)
            if rows < self.chunk_rows and buffered <= keep:
                fullest = rows
                break
            send(path, column, False)
            buffered -= rows
            sent = True
        if sent:  # what the sends freed: see _flush_due
            allocators.release_freed()
        self._buffered = buffered
        self._check_at = min(buffered + self.chunk_rows - fullest, self.max_buffered_rows)


def attach_to_runtime(runtime: Runtime, recorder: RigRecorder, repeat: bool = True) -> None:
    """Record a live runtime. Everything runs in the simulation thread, where the rig may be
    read: events after each batch (each at its own time), and a snapshot whenever a sample is
    due. Samples need a hook that runs after every simulation step (``add_step_listener``,
    see docs/recording.md "Live sessions"); without one they are taken after batches with
    events only. ``repeat``: a sample due while the rig's revision has not moved repeats the
    last one instead of taking a snapshot (the same rows; "Repeated samples")."""
    rig = runtime.rig
    recorder.al_status = event_text.al_status_reader(rig.devices)
    recorder.load_count = lambda: rig.loads
    recorder.scenario_of = lambda: rig.scenario

    def on_batch(events: list[Event]) -> None:
        t_us = rig.clock.now_us
        due = not per_step and recorder.sample_due(t_us)
        recorder.observe(t_us, rig.snapshot() if due else None, events)

    sampled = [-1]  # the rig revision of the last snapshot sampled

    def on_step(t_us: int) -> None:
        if recorder.sample_due(t_us):
            # The same revision: the devices are as that snapshot showed them, bar counters
            # the recording does not carry (docs/recording.md "Repeated samples").
            if repeat and rig.revision == sampled[0] and recorder.resample(t_us):
                return
            sampled[0] = rig.revision
            recorder.observe(t_us, rig.snapshot(), [])

    add_step_listener = getattr(runtime, "add_step_listener", None)
    per_step = add_step_listener is not None
    if add_step_listener is not None:
        add_step_listener(on_step, quiet_until=recorder.quiet_until)
    runtime.add_listener(on_batch)
    # The state before the first batch (and the blueprint) even if nothing happens for a while.
    runtime.submit(lambda: recorder.observe(rig.clock.now_us, rig.snapshot(), []))


def scenario_observer(recorder: RigRecorder) -> Callable[[Rig, list[Event]], None]:
    """A per-simulation-step hook for a headless run: ``hook(rig, events_of_the_step)``."""

    def on_tick(rig: Rig, events: list[Event]) -> None:
        if recorder.al_status is None:
            recorder.al_status = event_text.al_status_reader(rig.devices)
            recorder.load_count = lambda: rig.loads
            recorder.scenario_of = lambda: rig.scenario
        t_us = rig.clock.now_us
        recorder.observe(t_us, rig.snapshot() if recorder.sample_due(t_us) else None, events)

    return on_tick
