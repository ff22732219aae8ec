"""Process A's side of the EtherCAT wire: the rig's line behind process B's emulated ESCs.

:class:`WireBridge` describes the slaves of the rig's ``[master] line`` (their faces), starts
process B (``wire_process.run``) with those descriptions, switches the built-in master to
external mode and then carries messages both ways (tags in :mod:`app.ethercat_wire.messages`):

- a pump thread only moves messages between the pipe and two queues;
- everything that touches a model runs in the simulation thread, in a step listener: AL
  control writes go to the master's ``external_request`` (the slave model decides), mailbox
  messages to the slave's :class:`~app.ethercat_wire.coe.CoeServer`, SM2 images to its face,
  frame counts to ``external_frame`` (one master cycle apart, :class:`_FrameClock`, so a
  model sees the master's cycle, not the report bursts), statistics to ``external_stats``;
- back to B go the AL status / code when they change, the SM3 image when it changes (packed
  when a frame is handed to the model, at most every ``INPUTS_PERIOD_US``), emergencies as
  CoE mailbox messages, ``link`` when a slave drops off the line (cable pulled, powered
  off: from that position on nothing answers), ``silent`` when a slave on the frames' path
  stops or starts answering (its ESC passes the frames on: the drive with c9 != 11), and
  each slave's ESC error counters
  0x0300-0x0313 as the model counts them (``esc_errors``, when they changed, looked at every
  ``ESC_ERRORS_PERIOD_US``); a master's write there comes back as ``esc_errors_write`` and
  clears the model's (``external_esc_write``), answered with its number;
- the master's damaged cables go to B (``damage``, with the seed of the generator B draws
  their crossings from, ``frame_seed``, and the run), which spoils the wire master's frames as
  the model says (damage.py); what that counted comes back as ``esc_counts`` batches, added to
  the model's counters (``external_esc_counts``), and ``esc_errors`` names the last batch
  applied.

Positions are 0-based line positions. A scenario load resets the rig in place (the same
master object, its fresh state not in external mode; ``Rig.loads`` counts the loads): the
bridge attaches again, switches the master to external mode and starts a new run (the clock
went back to 0: frame and report timing start again; B gets the damage and seed again and
drops what the old run counted; batches and statistics of the old run are not taken).
"""

from __future__ import annotations

import collections
import logging
import multiprocessing
import socket
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from app.ethercat_wire import messages as msg
from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.description import SlaveDescription
from app.ethercat_wire.faces import Face, face_for
from app.rig_config import RigConfigError
from devices.ethercat import AlState
from devices.master.esc_errors import frame_seed
from devices.sync_managers import SmSetup

logger = logging.getLogger(__name__)

ETHERTYPE_ECAT = 0x88A4
READY_TIMEOUT_S = 30.0  # models ready (FastCAT scan) and process B up, each
ESC_ERRORS_PERIOD_US = 10_000  # error counters compared with what B holds this often
INPUTS_PERIOD_US = 2_000  # SM3 image refreshed with a frame, at most this often (sim. time)
UNKNOWN_STATE = 0x0012  # ETG.1000.6 / seed 000 §7.7 "Unknown requested state"
AL_STATE_MASK, AL_ACK = 0x0F, 0x10  # AL control: requested state, error acknowledge
AL_ID_REQUEST = 0x20  # AL control bit 5 (ETG.1000.6): the slave's face passes it on
# Frames handed to the models (docs in _FrameClock): a steady cycle at the reported rate.
PERIOD_SMOOTHING = 0.3  # weight of the newest report in the cycle estimate
CYCLE_TOLERANCE = 0.25  # B's cycle measurements within this of each other agree
ON_TIME_STEPS = 3  # a step at most this many step times after the previous one is on time
MAX_AL_DEFER_US = 100_000  # an AL control waits at most this long for the frames before it
ALIVE_REPORTS = 3  # the master counts as cycling this many report intervals after a report
MAX_OWED_REPORTS = 2  # frames owed beyond this many reports' worth are forgotten
MAX_FRAMES_PER_STEP = 16
PUMP_POLL_S = 0.001
OPTION = "--ethercat-if"

Spawn = Callable[[str, Sequence[SlaveDescription], Any], Any]


def check_interface(iface: str) -> None:
    """The interface exists and this process may open a raw EtherCAT socket on it."""
    try:
        socket.if_nametoindex(iface)
    except OSError:
        names = ", ".join(name for _i, name in socket.if_nameindex()) or "none"
        raise RigConfigError(OPTION, "", f"no network interface '{iface}' (interfaces: "
                                         f"{names})") from None
    try:
        sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHERTYPE_ECAT))
    except PermissionError:
        raise RigConfigError(OPTION, "", "a raw EtherCAT socket needs CAP_NET_RAW: run as "
                                         "root, or give Python the capability (sudo setcap "
                                         "cap_net_raw+ep <the python binary>)") from None
    sock.close()


def spawn_wire_process(iface: str, descriptions: Sequence[SlaveDescription], conn: Any) -> Any:
    """Process B in a fresh interpreter (the ``spawn`` start method of the wire contract)."""
    from app.ethercat_wire import wire_process

    ctx = multiprocessing.get_context("spawn")
    proc = ctx.Process(target=wire_process.run, args=(iface, list(descriptions), conn),
                       name="fieldrig-ethercat-wire", daemon=True)
    proc.start()
    return proc


@dataclass
class _FrameClock:
    """When to hand one slave's model a process-data frame.

    B reports how many frames a slave saw since its last report (every 10 ms of wall time).
    Handing them over in bursts would leave cycles without a frame: the TRS-CAT runs SYNC0 on
    the cycle the master wrote to 0x09A0 (``("dc", ...)`` -> ``configure_dc``) and counts
    SYNC0 cycles without a frame as sync errors (seed 001 §9.1.1, §9.3.7). So the frames go
    out one master cycle apart: the cycle is the reported rate in wall time (smoothed; a
    simulated microsecond is a wall microsecond at speed 1, and a clock that falls behind
    under load must not make the master look faster), for as long as reports keep saying
    that the master cycles. The count owed keeps the total close to what B saw; frames the
    simulation cannot keep up with are forgotten rather than handed over in a burst.
    """

    period_us: float = 0.0
    next_us: float = 0.0
    owed: int = 0
    alive_until: float = 0.0  # monotonic wall time
    measured: bool = False  # period_us is B's own measurement (``master_cycle``)
    candidate: float = 0.0  # a measurement far from period_us, adopted if the next agrees

    def report(self, n: int, span_s: float, now_us: int, wall: float) -> None:
        if n <= 0:
            return
        if not self.measured:  # a rough estimate until B's first measurement comes
            sample = span_s * 1e6 / n
            self.period_us = sample if not self.period_us else \
                (1 - PERIOD_SMOOTHING) * self.period_us + PERIOD_SMOOTHING * sample
        self.owed = min(self.owed + n, MAX_OWED_REPORTS * n)
        self.alive_until = wall + ALIVE_REPORTS * msg.CYCLE_REPORT_S
        if self.next_us < now_us - self.period_us:
            self.next_us = now_us  # the master (re)starts: no catching up on the pause

    def restart(self) -> None:
        """The simulated clock went back (a scenario load): the next frame at once, none owed
        from the old run; B's cycle measurement stays (the wire master did not change)."""
        self.next_us, self.owed = 0.0, 0

    def master_cycle(self, cycle_us: float) -> None:
        """B's mean process-data period over its last stats interval, on B's own clock. The
        estimate from the reports is only as good as A's timing of them: a starved pump or a
        busy simulation thread takes several at once (spans near 0), and B merges the counts
        of reports A could not take: that made the period look like 1 ms at a 4 ms cycle.
        A mean over a window in which the master started or paused is too long: a value far
        from the present one (and the first one: the window the master started in, 25 ms seen
        at a 4 ms cycle) is taken only when the very next measurement agrees with it (two
        windows cut by a pause, e.g. around config_map, would otherwise agree on 20 ms).
        """
        if cycle_us <= 0:
            self.candidate = 0.0  # no frames: the next measurement is not "the next" one
            return
        if (self.measured and _close(cycle_us, self.period_us)) or \
                _close(cycle_us, self.candidate):
            self.period_us, self.measured, self.candidate = float(cycle_us), True, 0.0
        else:
            self.candidate = float(cycle_us)

    def due(self, now_us: int, wall: float) -> int:
        """Frames to hand over at ``now_us``."""
        if not self.period_us or (self.owed <= 0 and wall > self.alive_until):
            return 0
        count = 0
        while self.next_us <= now_us and count < MAX_FRAMES_PER_STEP:
            count += 1
            self.next_us += self.period_us
            self.owed = max(0, self.owed - 1)
        if self.next_us <= now_us:
            self.next_us = now_us + self.period_us
        return count


def _close(a: float, b: float) -> bool:
    return b > 0 and abs(a - b) <= CYCLE_TOLERANCE * b


@dataclass
class _Slave:
    position: int
    model: Any
    face: Face
    coe: CoeServer
    status: tuple[int, int] | None = None  # last AL status / code sent
    inputs: bytes | None = None  # last SM3 image sent
    # (starts, configured station alias) B was last told (the description's, then sent): a new
    # start reloads 0x0012 (None: from the stored SII word 4)
    alias: tuple[int, int | None] | None = None
    inputs_due_us: int = 0
    esc_errors: bytes = bytes(20)  # 0x0300-0x0313 last sent (B powers on with zeros)
    clock: _FrameClock = field(default_factory=lambda: _FrameClock())


class WireBridge:
    def __init__(self, runtime: Any, iface: str, spawn: Spawn = spawn_wire_process) -> None:
        self.runtime = runtime
        self.iface = iface
        self._spawn = spawn
        self._conn: Any = None
        self.process: Any = None
        self._inbox: collections.deque[tuple[Any, ...]] = collections.deque()
        self._outbox: collections.deque[tuple[Any, ...]] = collections.deque()
        self._stop = threading.Event()  # the pump and the step listener end
        self._stopped = False  # stop() done
        self._pump_thread: threading.Thread | None = None
        self._slaves: list[_Slave] = []
        self._master: Any = None
        self._run: int | None = None  # the rig's loads when attached (B's "run")
        self._link_down: int | None = None
        self._silent: frozenset[int] = frozenset()  # B's silent slaves (it starts with none)
        self._esc_errors_due_us = 0
        self._esc_seq = 0  # the last esc_counts batch or esc_errors_write the model took
        self._seed: int | None = None  # of the crossings B draws (frame_seed), per master
        self._damage: tuple[dict[int, float], int | None, int | None] | None = None  # last sent
        self._last_report_wall: float | None = None  # when B's last frame report came
        self._step_wall: float | None = None  # the wall time the last step stood for
        self._step_us: int | None = None
        self._call_wall: float | None = None  # when the last step listener call ran
        self._deferred_since: int | None = None  # an AL control held since (sim. time)
        self.descriptions: list[SlaveDescription] = []
        self.ready_iface: str | None = None
        self.errors: collections.deque[str] = collections.deque(maxlen=50)
        self.dc: dict[int, dict[str, int]] = {}
        self.stats: dict[str, Any] = {}

    # ---- life cycle (caller's thread) -------------------------------------------------------
    def start(self, timeout_s: float = READY_TIMEOUT_S) -> None:
        """Describe the line, start process B, wait for it, then pump."""
        self._call(self._attach)
        deadline = time.monotonic() + timeout_s
        while not self._call(self._all_ready) and time.monotonic() < deadline:
            time.sleep(0.05)  # a FastCAT scans its modules for seconds after power-up
        self.descriptions = self._call(self._describe)
        parent, child = multiprocessing.get_context("spawn").Pipe()
        self._conn = parent
        self.process = self._spawn(self.iface, self.descriptions, child)
        self._await_ready(deadline=time.monotonic() + timeout_s)
        self._call(lambda: self.runtime.add_step_listener(self._on_step, realtime=True))
        self._pump_thread = threading.Thread(target=self._pump, name="fieldrig-ethercat-pump",
                                             daemon=True)
        self._pump_thread.start()
        logger.info("EtherCAT wire on %s: %d slaves", self.ready_iface,
                    len(self.descriptions))

    def _await_ready(self, deadline: float) -> None:
        while time.monotonic() < deadline:
            if not self._conn.poll(0.05):
                continue
            message = self._conn.recv()
            if message[0] == msg.READY:
                self.ready_iface = message[1]
                return
            if message[0] == msg.ERROR:
                self._terminate()
                raise RigConfigError(OPTION, "", f"the EtherCAT wire process failed: "
                                                 f"{message[1]}")
            self._inbox.append(message)
        self._terminate()
        raise RigConfigError(OPTION, "", "the EtherCAT wire process did not start in time")

    def stop(self) -> None:
        if self._stopped:
            return
        self._stopped = True
        self._stop.set()
        if self._pump_thread is not None:
            self._pump_thread.join(timeout=2)
        try:
            if self._conn is not None:
                self._conn.send((msg.STOP,))
        except (OSError, EOFError, ValueError):
            pass
        if self.process is not None and hasattr(self.process, "join"):
            self.process.join(timeout=2)
        self._terminate()
        master = self._master
        if master is not None and hasattr(master, "set_external"):
            self.runtime.submit(lambda: master.set_external(False))

    def _terminate(self) -> None:
        proc = self.process
        if proc is not None and hasattr(proc, "is_alive") and proc.is_alive():
            proc.terminate()
            proc.join(timeout=2)

    def _call(self, fn: Callable[[], Any]) -> Any:
        return self.runtime.submit(fn).result(timeout=10)

    # ---- the pump (only moves messages) -----------------------------------------------------
    def _pump(self) -> None:
        conn = self._conn
        try:
            while not self._stop.is_set():
                while conn.poll(PUMP_POLL_S):
                    self._inbox.append(conn.recv())
                while self._outbox:
                    conn.send(self._outbox.popleft())
        except (EOFError, OSError) as exc:
            if not self._stop.is_set():
                logger.error("EtherCAT wire process gone: %s; the built-in master takes the "
                             "line back", exc)
                self.errors.append(f"wire process gone: {exc}")
                self._stop.set()
                master = self._master
                if master is not None and hasattr(master, "set_external"):
                    self.runtime.submit(lambda: master.set_external(False))

    def _send(self, *message: Any) -> None:
        self._outbox.append(message)

    # ---- simulation thread ------------------------------------------------------------------
    def _attach(self) -> None:
        master = self.runtime.rig.devices.get("master")
        if master is None:
            raise RigConfigError(OPTION, "", "the rig has no EtherCAT line ([master] line)")
        run = getattr(self.runtime.rig, "loads", 0)
        if self._master is not None and (master is not self._master or run != self._run):
            self._new_run()
        self._master, self._run = master, run
        rng = getattr(master, "rng", None)
        self._seed = frame_seed(rng) if rng is not None else None
        if hasattr(master, "set_external"):
            master.set_external(True)
        else:
            logger.warning("the built-in master has no external mode: it keeps driving the "
                           "line next to the wire master")
        line = [link.slave for link in master.links]
        old = {id(s.model): s for s in self._slaves}
        by_position = dict(enumerate(self._slaves))
        self._slaves = [old.get(id(model)) or self._new_slave(pos, model, by_position.get(pos))
                        for pos, model in enumerate(line)]
        for pos, s in enumerate(self._slaves):
            s.position = pos

    def _new_run(self) -> None:
        """The rig was loaded afresh: its clock went back to 0 and its master is a fresh one,
        which must not see what the old run's frames counted."""
        self._damage = None  # sent again: B starts the crossings from the seed, counts afresh
        self._esc_errors_due_us = 0
        self._deferred_since = None
        for s in self._slaves:
            s.inputs_due_us = 0
            s.clock.restart()

    @staticmethod
    def _new_slave(position: int, model: Any, was: _Slave | None = None) -> _Slave:
        """A fresh face for ``model``; ``was``: the slave B holds at this position (a load
        gives the master fresh slave objects), whose state B keeps until told otherwise."""
        face = face_for(model)
        s = _Slave(position, model, face, CoeServer(face, model))
        if was is not None:
            s.status, s.inputs, s.alias = was.status, was.inputs, was.alias
            s.esc_errors, s.clock = was.esc_errors, was.clock
        return s

    def _all_ready(self) -> bool:
        return all(s.face.ready(s.model) for s in self._slaves)

    def _describe(self) -> list[SlaveDescription]:
        descriptions = [s.face.describe(s.model) for s in self._slaves]
        for s, desc in zip(self._slaves, descriptions, strict=True):
            s.alias = (s.face.power_ups(s.model), desc.station_alias)
        return descriptions

    def _on_step(self, now_us: int) -> None:
        if self._stop.is_set():
            return
        rig = self.runtime.rig
        master = rig.devices.get("master")
        if master is not self._master or getattr(rig, "loads", 0) != self._run or \
                not getattr(master, "external", True):
            self._attach()  # a scenario load (the rig reset in place) or a new rig
        while self._inbox and not self._defer(self._inbox[0], now_us):
            self._handle(self._inbox.popleft(), now_us)
        if self._inbox:  # held: B's statistics (the cycle) still count meanwhile
            for message in [m for m in self._inbox if m[0] == msg.STATS]:
                self._inbox.remove(message)
                self._handle(message, now_us)
        step_wall = self._wall_of_step(now_us)
        for s in self._slaves:
            self._serve(s, now_us, step_wall)
        self._relink()
        damage = (dict(getattr(self._master, "damaged", {})), self._seed, self._run)
        if damage != self._damage and damage[1] is not None:
            self._damage = damage
            self._send(msg.DAMAGE, *damage)
        if now_us >= self._esc_errors_due_us:
            self._esc_errors_due_us = now_us + ESC_ERRORS_PERIOD_US
            for s in self._slaves:
                self._sync_esc_errors(s)

    def _relink(self) -> None:
        """Where the frames stop (``link``) and which slaves on their way do not answer
        (``silent``), as the built-in master's line has it: a powered ESC passes frames on
        whatever its application does (``frame_path``), so a silent slave does not cut off
        the slaves behind it."""
        path = getattr(self._master, "frame_path", None)
        reach = path() if path is not None else next(
            (s.position for s in self._slaves if not s.face.reachable(s.model)),
            len(self._slaves))  # a master without the line's physics: the answers decide
        down = reach if reach < len(self._slaves) else None
        if down != self._link_down:
            self._send(msg.LINK, 0, True)
            if down is not None:
                self._send(msg.LINK, down, False)
            self._link_down = down
        silent = frozenset(s.position for s in self._slaves[:reach]
                           if not s.face.reachable(s.model))
        for position in sorted(silent ^ self._silent):
            self._send(msg.SILENT, position, position in silent)
        self._silent = silent

    def _sync_esc_errors(self, s: _Slave, counted: bool = False) -> None:
        """The model's counters to B when they changed, or when a batch or a write of B's was
        just taken (``counted``: B stops adding the batch on top, applying the write again)."""
        links = getattr(self._master, "links", None)
        if links is None or s.position >= len(links) or not hasattr(links[s.position], "esc"):
            return
        data = links[s.position].esc.registers()
        if data != s.esc_errors or counted:
            s.esc_errors = data
            self._send(msg.ESC_ERRORS, s.position, data, self._esc_seq)

    def _esc_counts(self, seq: int, counts: dict[int, bytes], run: int | None) -> None:
        self._esc_seq = seq
        add = getattr(self._master, "external_esc_counts", None)
        if add is None or run != self._run:  # the old run's: not the fresh model's (B dropped
            return                            # the batch too)
        for position, data in counts.items():
            s = self._slave(int(position))
            if s is not None:
                add(s.position, bytes(data))
                self._sync_esc_errors(s, counted=True)

    def _defer(self, message: tuple[Any, ...], now_us: int) -> bool:
        """Hold an AL control write (and what came after it) while frames the master sent
        before it are still owed to the model: a simulation that lags takes B's frame reports
        and the request in one step, and the model must see those frames first (the TRS-CAT
        checks at SAFEOP -> OP that its SYNC0 events took frames, seed 001 §9.3.1; the others
        want valid outputs). At most ``MAX_AL_DEFER_US`` of simulated time."""
        if message[0] != msg.AL_CONTROL:
            return False
        s = self._slave(message[1])
        if s is None or s.clock.owed <= 0 or not s.clock.period_us:
            self._deferred_since = None
            return False
        if self._deferred_since is None:
            self._deferred_since = now_us
        if now_us - self._deferred_since >= MAX_AL_DEFER_US:
            self._deferred_since = None
            return False
        return True

    def _wall_of_step(self, now_us: int) -> float:
        """The wall time this simulated step stands for: the wall clock, except while the
        simulation catches up after a stall, when its steps stand for the (past) wall times
        they were late for. Whether the master still cycles is judged at that time, so a
        stall of the simulation thread does not leave steps without frames (3 of them in a
        row are a TRS-CAT sync error) while B's reports wait for the pump."""
        wall = time.monotonic()
        last_wall, last_us, last_call = self._step_wall, self._step_us, self._call_wall
        self._call_wall = wall
        if last_wall is None or last_us is None or last_call is None or now_us <= last_us:
            step_wall = wall
        else:
            speed = float(getattr(self.runtime, "speed", 1.0) or 1.0)
            step_s = (now_us - last_us) / 1e6 / speed
            if step_s <= wall - last_call <= ON_TIME_STEPS * step_s:
                step_wall = wall  # on time: the simulation keeps up
            else:  # a stall, or the burst of steps after one
                step_wall = min(wall, last_wall + step_s)
        self._step_wall, self._step_us = step_wall, now_us
        return step_wall

    def _serve(self, s: _Slave, now_us: int, step_wall: float) -> None:
        handed = s.clock.due(now_us, step_wall)
        for _ in range(handed):
            self._frame(s, now_us)
        for frame in s.face.take_emergencies(s.model):
            self._send(msg.MAILBOX_REPLY, s.position, s.coe.emergency(frame))
            note = getattr(self._master, "external_emergency", None)
            if note is not None:
                note(s.position, frame)
        status = s.face.al_status(s.model)
        if status != s.status:
            s.status = status
            self._send(msg.AL_STATUS, s.position, *status)
        alias = (s.face.power_ups(s.model), s.face.station_alias(s.model))
        if alias != s.alias:  # a start (B starts with the description's)
            s.alias = alias
            self._send(msg.ALIAS, s.position, alias[1])
        if handed and now_us >= s.inputs_due_us:  # the inputs a frame would carry
            s.inputs_due_us = now_us + INPUTS_PERIOD_US
            data = s.face.inputs(s.model)
            if data and data != s.inputs:
                s.inputs = data
                self._send(msg.INPUTS, s.position, data)

    def _frame(self, s: _Slave, now_us: int) -> None:
        external = getattr(self._master, "external_frame", None)
        if external is not None:
            external(s.position)
        else:
            s.model.exchange_frame(now_us)

    def _slave(self, position: int) -> _Slave | None:
        if 0 <= position < len(self._slaves):
            return self._slaves[position]
        logger.info("EtherCAT wire: no slave at line position %s", position)
        return None

    def _handle(self, message: tuple[Any, ...], now_us: int) -> None:
        tag = message[0]
        if tag == msg.READY:
            self.ready_iface = message[1]
        elif tag == msg.ERROR:
            logger.error("EtherCAT wire: %s", message[1])
            self.errors.append(str(message[1]))
        elif tag == msg.CYCLE:
            self._schedule_frames(message[1], now_us)
        elif tag == msg.STATS:
            self._stats(message[1])
        elif tag == msg.ESC_COUNTS:
            self._esc_counts(int(message[1]), message[2], message[3])
        elif tag == msg.ESC_ERRORS_WRITE:
            s = self._slave(message[1])
            write = getattr(self._master, "external_esc_write", None)
            self._esc_seq = int(message[4])
            if s is not None and write is not None:
                write(s.position, int(message[2]), int(message[3]))
                self._sync_esc_errors(s, counted=True)  # acknowledged: B stops applying it
        elif tag in (msg.AL_CONTROL, msg.MAILBOX, msg.OUTPUTS, msg.DC, msg.SM):
            s = self._slave(message[1])
            if s is not None:
                self._for_slave(s, tag, message[2])
        else:
            logger.info("EtherCAT wire: unknown message %r", tag)

    def _for_slave(self, s: _Slave, tag: str, payload: Any) -> None:
        if tag == msg.AL_CONTROL:
            self._al_control(s, int(payload))
        elif tag == msg.MAILBOX:
            for reply in s.coe.handle(bytes(payload)):
                self._send(msg.MAILBOX_REPLY, s.position, reply)
        elif tag == msg.OUTPUTS:
            s.face.apply_outputs(s.model, bytes(payload))
        elif tag == msg.SM:
            s.face.configure_sync_managers(s.model, [SmSetup(*r) for r in payload])
        else:
            self.dc[s.position] = dict(payload)
            s.face.configure_dc(s.model, dict(payload))
            note = getattr(self._master, "external_dc", None)
            if note is not None:
                note(s.position, dict(payload))

    def _al_control(self, s: _Slave, value: int) -> None:
        try:
            state = AlState(value & AL_STATE_MASK)
        except ValueError:
            s.face.refuse_unknown_state(s.model, UNKNOWN_STATE)
        else:
            external = getattr(self._master, "external_request", None)
            if external is not None:
                external(s.position, state)  # the master notes it and asks the slave model
            else:
                s.face.request_state(s.model, state)
        s.face.request_id(s.model, bool(value & AL_ID_REQUEST))

    def _schedule_frames(self, counts: dict[int, int], now_us: int) -> None:
        """B's frame counts since its last report, over the wall time since then (a report
        after a pause covers at most two report periods: B reports while frames come)."""
        wall = time.monotonic()
        last, self._last_report_wall = self._last_report_wall, wall
        span = min(wall - last, 2 * msg.CYCLE_REPORT_S) if last is not None else \
            msg.CYCLE_REPORT_S
        for position, n in counts.items():
            s = self._slave(int(position))
            if s is not None:
                s.clock.report(int(n), span, now_us, wall)

    def _stats(self, stats: dict[str, Any]) -> None:
        self.stats = dict(stats)
        for s in self._slaves:
            s.clock.master_cycle(float(stats.get("cycle_us", 0)))
        external = getattr(self._master, "external_stats", None)
        if external is not None and stats.get("run") == self._run:  # not the old run's counts
            external(frames=int(stats.get("frames", 0)),
                     lost_frames=int(stats.get("lost_frames", 0)),
                     cycle_us=round(float(stats.get("cycle_us", 0))),
                     wkc_errors=int(stats.get("wkc_errors", 0)))


def start_wire(runtime: Any, iface: str, rigs: int = 1) -> WireBridge:
    """``--ethercat-if IFACE``: check the interface, then run the wire (RigConfigError if not)."""
    if rigs != 1:
        raise RigConfigError(OPTION, "", "one rig per interface: serve a single rig")
    check_interface(iface)
    bridge = WireBridge(runtime, iface)
    bridge.start()
    print(f"FieldRig: EtherCAT wire on {bridge.ready_iface} ({len(bridge.descriptions)} "
          f"slaves)", flush=True)
    return bridge
