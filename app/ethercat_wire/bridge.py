"""Process A's side of the EtherCAT wire: the rig's line behind process B's emulated ESCs.

:class:`WireBridge` describes the slaves of the rig's ``[master] line`` (their faces), starts
process B (``wire_process.run``) with those descriptions, switches the built-in master to
external mode and then carries messages both ways (tags in :mod:`app.ethercat_wire.messages`):

- a pump thread only moves messages between the pipe and two queues;
- everything that touches a model runs in the simulation thread, in a step listener: AL
  control writes go to the master's ``external_request`` (the slave model decides), a station
  address the wire master wrote (0x0010) to ``external_station_address`` (given again to the
  fresh model after a load), mailbox messages to the slave's
  :class:`~app.ethercat_wire.coe.CoeServer`, SM2 images to its face, frame counts to
  ``external_frame`` (one master cycle apart,
  :class:`~app.ethercat_wire.frame_clock.FrameClock`, so a model sees the master's cycle,
  not the report bursts), statistics to ``external_stats``;
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

This file holds the bridge's life cycle, the pump and the step listener; what comes from B is
``from_wire.py``, what goes to B ``to_wire.py`` (both mixins of :class:`WireBridge`), the
per-slave state ``wire_slave.py``, the frame pacing ``frame_clock.py``, the interface check
and process B's start ``launch.py``.
"""

from __future__ import annotations

import collections
import logging
import multiprocessing
import threading
import time
from collections.abc import Callable
from typing import Any

from app.ethercat_wire import messages as msg
from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.description import SlaveDescription
from app.ethercat_wire.faces import face_for
from app.ethercat_wire.from_wire import FromWire
from app.ethercat_wire.launch import OPTION, Spawn, check_interface, spawn_wire_process
from app.ethercat_wire.to_wire import ToWire
from app.ethercat_wire.wire_slave import WireSlave
from app.rig_config import RigConfigError
from devices.master.esc_errors import frame_seed

logger = logging.getLogger(__name__)

READY_TIMEOUT_S = 30.0  # models ready (FastCAT scan) and process B up, each
ESC_ERRORS_PERIOD_US = 10_000  # error counters compared with what B holds this often
ON_TIME_STEPS = 3  # a step at most this many step times after the previous one is on time
PUMP_POLL_S = 0.001


class WireBridge(FromWire, ToWire):
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
        self._slaves: list[WireSlave] = []
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
            self._give_station(s)  # a fresh model (a load): the address B's ESC still holds

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
    def _new_slave(position: int, model: Any, was: WireSlave | None = None) -> WireSlave:
        """A fresh face for ``model``; ``was``: the slave B holds at this position (a load
        gives the master fresh slave objects), whose state B keeps until told otherwise."""
        face = face_for(model)
        s = WireSlave(position, model, face, CoeServer(face, model))
        if was is not None:
            s.status, s.inputs, s.alias = was.status, was.inputs, was.alias
            s.esc_errors, s.clock, s.station = was.esc_errors, was.clock, was.station
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
