"""The built-in EtherCAT master (seed 003) and its TwinCAT-style logger (seed 000 §7.1, §7.7).

It reads a network description (devices/master/network.py; derived from the rig's line when
no file is given), waits for link on its port (cable 0 plugged, the first slave powered),
exchanges one frame per cycle, brings every slave INIT -> PREOP -> SAFEOP -> OP with the init
commands and checks of each transition (devices/master/startup.py), manages distributed clocks
(devices/master/dc.py), keeps each slave's diagnostic structure (by position and by physical
address) and raises the seed's events with the ECAT_Notify / ECAT_Resync hooks. Line faults:
cables pulled between slaves, slaves powered off, frames lost.

Timing: a requested transition is checked ``check_delay_us`` after the request. The default,
141 ms, is the gap the §7.7 log shows between "abnormal state change" (280 ms) and "'PREOP to
SAFEOP' failed!" (421 ms). INIT -> PREOP waits for the slave's internal-bus scan (seconds) up
to ``state_timeout_us``. Station addresses 1001, 1002, ... as TwinCAT assigns them, unless the
description says otherwise. See docs/ethercat-master.md.
"""

from __future__ import annotations

import collections
import datetime as dt
import random
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from devices.device import Action, CommandError, DeviceModel
from devices.esm import AlStatusView
from devices.ethercat import AL_STATUS_ERROR_FLAG, AlState, parse_emergency_frame
from devices.events import (
    CoeEmergency,
    Event,
    LogLine,
    Resync,
    SlaveStateChange,
    StateChanged,
)
from devices.master.actions import MASTER_ACTIONS
from devices.master.dc import START_DELAY_US, DcState, DcUnit
from devices.master.esc_errors import EscErrors
from devices.master.hooks import Callback, Hooks
from devices.master.line import LOST, LineMixin
from devices.master.links import RANK, Slave, SlaveLink, next_state
from devices.master.log_styles import Entry, arrange, is_late, render, same_group
from devices.master.network import Mapping as NetworkMapping
from devices.master.network import MasterParameters, SlaveDescription
from devices.master.spans import SpanMixin
from devices.master.startup import StartupMixin
from devices.master.still import StillCounts
from devices.master.view import ViewMixin

TWINCAT_PORT = 65535  # seed 000 §7.1 / §7.7: "Server (porta) (65535)"
FIRST_STATION_ADDRESS = 1001  # §7.1 / §7.7: "'Box 1 (FastCAT)' (1001)"
STATE_CHECK_DELAY_US = 141_000  # §7.7 log: 14.51.30 280 ms -> 421 ms
STATE_TIMEOUT_US = 10_000_000  # covers a 16-module scan (§3: "qualche secondo")
LOG_LENGTH = 500
DEFAULT_EPOCH = dt.datetime(2019, 11, 12, 14, 51, 30)  # the §7.7 log's date
DC_MACHINE = "dc"  # StateChanged.machine of the master's DC management

__all__ = ["DEFAULT_EPOCH", "FIRST_STATION_ADDRESS", "LOG_LENGTH", "STATE_CHECK_DELAY_US",
           "STATE_TIMEOUT_US", "TWINCAT_PORT", "EtherCatMaster", "Slave", "next_state",
           "twincat_timestamp"]


def twincat_timestamp(epoch: dt.datetime, t_us: int) -> str:
    """``12/11/2019 14.51.30 421 ms``: the TwinCAT logger's format (seed 000 §7.1, §7.7)."""
    at = epoch + dt.timedelta(microseconds=t_us)
    return f"{at:%d/%m/%Y %H.%M.%S} {at.microsecond // 1000:03d} ms"


_LINE_PARAMS = frozenset({"cable", "position"})  # line positions 0 .. slaves - 1
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_SAFEOP, _COMPENSATING = AlState.SAFEOP, DcState.COMPENSATING


class EtherCatMaster(LineMixin, StartupMixin, SpanMixin, ViewMixin, DeviceModel):
    KIND = "master"
    SKIP_STILL = True  # False: every part of every step in full (test_still_master.py)
    ACTIONS: ClassVar[Mapping[str, Action]] = MASTER_ACTIONS

    def __init__(self, device_id: str = "master", rng: random.Random | None = None,
                 slaves: Sequence[Slave] = (), retry_interval_us: int = 2_000_000,
                 port: int = TWINCAT_PORT, epoch: dt.datetime = DEFAULT_EPOCH,
                 check_delay_us: int = STATE_CHECK_DELAY_US,
                 state_timeout_us: int = STATE_TIMEOUT_US,
                 descriptions: Sequence[SlaveDescription | None] | None = None,
                 mapping: NetworkMapping | None = None,
                 dc_slaves: Sequence[bool] | None = None,
                 step_us: int | None = None) -> None:
        super().__init__(device_id=device_id, rng=rng or random.Random(0))
        if descriptions is not None and len(descriptions) != len(slaves):
            raise ValueError(f"the network description has {len(descriptions)} slaves, the "
                             f"line {len(slaves)}")
        self.links = [SlaveLink(s, position=i) for i, s in enumerate(slaves)]
        for i, link in enumerate(self.links):
            desc = descriptions[i] if descriptions is not None else None
            link.description = desc
            link.dc_derived = bool(dc_slaves[i]) if dc_slaves is not None else False
            link.slave.station_address = desc.station_address if desc is not None \
                else FIRST_STATION_ADDRESS + i
            if desc is not None and desc.name:
                link.slave.box_name = desc.name
        self.mapping = mapping
        # Without a mapping the master cycles once a rig step (the rig passes ``step_us``;
        # docs/ethercat-master.md start-up 3): a fixed 1 ms would skip steps at a finer step
        # and claim a cycle (SYNC0, stats) it cannot keep at a coarser one.
        params = mapping.parameters if mapping is not None else \
            MasterParameters() if step_us is None else MasterParameters(cycle_us=step_us)
        self.cycle_us = params.cycle_us
        self.retry_interval_us = retry_interval_us
        self.port = port
        self.epoch = epoch
        self.check_delay_us = check_delay_us
        self.state_timeout_us = state_timeout_us
        self.target = AlState.OP
        self.log: collections.deque[dict[str, Any]] = collections.deque(maxlen=LOG_LENGTH)
        self.entries: collections.deque[Entry] = collections.deque(maxlen=LOG_LENGTH)
        self.log_style = "twincat"
        # Lines the style prints after the slave's other lines of the same step (log_styles.LATE),
        # held until that slave's run of lines ends; empty between steps.
        self._held: list[Entry] = []
        self.cables = [True] * len(self.links)
        self.phys_in = [True] * len(self.links)  # the IN / OUT links last given to the slaves
        self.phys_out = [True] * len(self.links)
        self.dc = DcUnit(window_ns=params.dc_window_ns)
        # DC slaves wait in SAFEOP until COMPENSATING (seed 003: START_TIME is "the first time
        # the slaves implement I/O"); the unit starts IDLE.
        self.dc_hold = True
        self.hooks = Hooks()
        self.external = False
        self.frames = 0
        self.lost_frames = 0
        self.to_lose = 0
        self.damaged: dict[int, float] = {}  # cable -> share of its crossings spoiled
        self.crc_unreported = 0  # frames lost (damaged cable, lose_frames) since the last line
        self.crc_report_us = 0  # no log line of those before
        self.next_cycle_us = 0
        self.network_op = False
        self.link_up = False
        # The ports' links were applied since the last step: the lost slaves' findings may move.
        self._links_moved = False
        self._bursting = False
        # Still steps (devices/master/still.py): the line as last applied, the states last
        # watched (None: watch again), the links that use DC (fixed by the description).
        self.skipped = StillCounts()
        self._line_cables: list[bool] = []
        self._line_powered: list[bool] = []
        self._line_plugs: list[tuple[bool, bool]] = []
        self._line_reach: list[bool] = []
        self._watched: list[AlState | None] | None = None
        self._slaves = tuple(link.slave for link in self.links)  # the line is fixed
        self._power_names = ("powered",) * len(self._slaves)
        self._power_defaults = (True,) * len(self._slaves)
        self._plug_names = ("plugs",) * len(self._slaves)
        self._plug_defaults = ((True, True),) * len(self._slaves)
        self._dc_links = [link for link in self.links if link.dc]
        self._uses_dc = [link.dc for link in self.links]
        # The step's loop, one row per position (the line is fixed): each slave's bound calls
        # made once here, so a cycle does not look up and bind three methods per slave again;
        # and whether its al_state is AlStatusView's property (``esm.state`` read fresh each
        # time), which the loop then reads without the property's call.
        for slave in self._slaves:  # a DC slave's span needs to know its frames will come
            if hasattr(slave, "frames_promised"):
                slave.frames_promised = self.frames_promised  # type: ignore[attr-defined]
        self._rows = tuple((link, link.position, link.slave, link.slave.reachable,
                            link.slave.exchange_frame, link.slave.take_emergencies, link.dc,
                            getattr(type(link.slave), "al_state", None) is AlStatusView.al_state)
                           for link in self.links)

    # ---- hooks (seed 003: ECAT_Notify, ECAT_Resync) -------------------------------------------
    def on_notify(self, callback: Callback) -> None:
        """Called with each master event after the diagnostic structures are updated."""
        self.hooks.notify.append(callback)

    def on_resync(self, callback: Callback) -> None:
        """Called with each Resync: a node or the whole network reached OP the first time."""
        self.hooks.resync.append(callback)

    # ---- commands ---------------------------------------------------------------------------
    def cmd_resync(self) -> None:
        """Every slave through INIT; ECAT_Resync fires again as they reach OP."""
        self.network_op, self._watched = False, None
        for link in self.links:
            if link.present:
                link.reached_op = False
                self._request(link, AlState.INIT)

    def cmd_set_target(self, state: str) -> None:
        self.target = AlState[state]
        for link in self.links:
            link.next_try_us = self.now_us

    def check_command(self, action: str, args: Mapping[str, Any],
                      module: int | None = None) -> dict[str, Any]:
        kwargs = super().check_command(action, args, module)
        # The line is fixed when the rig is built: a scenario's or an exercise's check before
        # the run refuses a position past its end, as the command would.
        for what in _LINE_PARAMS.intersection(kwargs):
            self._position(kwargs[what], what)
        return kwargs

    def _position(self, value: int, what: str) -> int:
        if not 0 <= value < len(self.links):
            raise CommandError(f"{what} {value}: the line has positions 0..{len(self.links) - 1}")
        return value

    def cmd_dc_fault(self, kind: str) -> None:
        self.dc.fault = kind
        self._slave_dc_fault(kind)

    def cmd_clear_dc_fault(self) -> None:
        self.dc.fault = None
        self._slave_dc_fault(None)

    def _slave_dc_fault(self, kind: str | None) -> None:
        """The slaves' own view of the fault (their sync-error paths), DC slaves only."""
        for link in self.links:
            setter = getattr(link.slave, "set_dc_fault", None)
            if link.dc and setter is not None:
                setter(kind)

    def cmd_set_log_style(self, style: str) -> None:
        self._flush_log()
        self.log_style = style
        self.log = collections.deque((self._row(e) for e in arrange(style, self.entries)),
                                     maxlen=LOG_LENGTH)

    # ---- external mode (a wire master drives the line, issue 8) -------------------------------
    def set_external(self, on: bool) -> None:
        """A wire master takes the line (``on``) or hands it back. Who drives the line is who
        gives each slave its station address: a slave that checks it (the FastCAT's address
        check, seed 000 §6.19) compares the ESC's 0x0010, 0 until the wire master writes it
        (:meth:`external_station_address`), or the built-in master's own setting (None)."""
        self.external = on
        for link in self.links:
            self._give_station(link.slave, 0 if on else None)

    @staticmethod
    def _give_station(slave: Slave, address: int | None) -> None:
        take = getattr(slave, "take_station_address", None)
        if take is not None:
            take(address)

    def external_station_address(self, position: int, address: int) -> None:
        """A wire master wrote a slave's configured station address (ESC 0x0010, ETG.1000.4):
        the address it gives that slave on the line. The master's own view (log lines, panel)
        keeps naming the slave by the built-in master's address."""
        self._give_station(self.links[self._position(position, "position")].slave, address)

    def external_request(self, position: int, state: AlState, ack: bool = False) -> None:
        """A wire master's AL control write: ``ack`` is its bit 4 (ETG.1000.6), as written."""
        link = self.links[self._position(position, "position")]
        link.requested = state
        link.slave.request_state(state, ack)

    def external_frame(self, position: int) -> None:
        """A wire master's frame reached ``position``: an exchange for a slave that answers;
        a slave that does not, powered, only sees it pass (its ESC forwards it, as in the
        step's loop: :meth:`_pass_silent`)."""
        link = self.links[self._position(position, "position")]
        if self._connected(position):
            slave = link.slave
            if slave.reachable():  # every exchange_frame tests it first: nothing lost
                slave.exchange_frame(self.now_us)
            elif self._powered(position):
                self._pass_silent(slave)
        self.frames += 1

    def external_emergency(self, position: int, frame: bytes) -> None:
        """An emergency the wire master read from a slave's mailbox: counted, logged, event."""
        link = self.links[self._position(position, "position")]
        code, register, data = parse_emergency_frame(frame)
        link.counters.emergencies += 1
        self._event(CoeEmergency(self.now_us, self.device_id, position=position,
                                 address=link.slave.station_address, code=code,
                                 register=register, data=data))
        self._log(link, "emergency", code=code, register=register, data=data)
        self._flush_log()  # outside a step: nothing else of this slave's instant follows

    def external_esc_write(self, position: int, ado: int, length: int) -> None:
        """A wire master's write into a slave's 0x0300-0x0313: the ESC clears those blocks."""
        self.links[self._position(position, "position")].esc.write(ado, length)

    def external_esc_counts(self, position: int, data: bytes) -> None:
        """What a damaged cable counted in a slave's ESC on a wire master's frames (the wire
        process ran them through run_frame): added to the counters here."""
        esc = self.links[self._position(position, "position")].esc
        esc.add(EscErrors.from_registers(data))

    def external_stats(self, frames: int, lost_frames: int, cycle_us: int,
                       wkc_errors: int) -> None:
        """The wire master's statistics, totals in this run. Its lost frames are the frames
        a damaged cable spoiled (the wire process sees no other loss): those new since the
        last report go the built-in master's way (per slave, events, log lines)."""
        self.frames, self.cycle_us = frames, cycle_us
        if lost_frames > self.lost_frames:
            self._lose_spoiled(lost_frames - self.lost_frames)
        for link in self.links:
            link.counters.wkc_errors = wkc_errors

    # ---- stepping ---------------------------------------------------------------------------
    def step(self, now_us: int) -> None:
        dt_us = now_us - self.now_us
        if dt_us < 0:  # DeviceModel.step, inline (every step: super() costs a lookup)
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {self.now_us})")
        self.now_us = now_us
        skip = self.SKIP_STILL
        reach = self._line(skip)
        rows = self._rows
        # The port's link is its PHY's: cable 0 in and the first slave's PHY powered. Whether
        # that slave answers is apart (a powered ESC passes frames on without its application).
        # A slave's reachable() has no side effect: position 0's answer serves twice.
        port_up = bool(rows) and reach[0] and self._line_powered[0]
        first = port_up and rows[0][3]()
        self.link_up = port_up
        cycle = now_us >= self.next_cycle_us
        if cycle:
            self.next_cycle_us = now_us + self.cycle_us
        external = self.external
        lost = cycle and not external and self.to_lose > 0 and port_up
        if lost:
            self._lose_frame()
        elif self.damaged and cycle and not external and port_up:  # healthy: one dict's truth
            lost = self._spoiled()  # the frame's physical path, answered or not
        elif self._bursting and cycle and not external and port_up:  # a frame back: report
            self._end_burst()
        exchange = cycle and not lost and not external
        target = self.target
        # The target of a DC slave (SAFEOP while DC holds): _target_of_dc, inlined.
        held = _SAFEOP if self.dc_hold and RANK[target] > RANK[_SAFEOP] else target
        # quiet: every slave present, reachable and left unserved, each in the state the last
        # watch saw (still.py): the watch and the DC unit's trigger may take their short way.
        watched = self._watched
        quiet = exchange and skip and watched is not None
        served = 0
        recovered = []
        lost_now = []
        missing_now = []
        for link, p, slave, reachable, exchange_frame, take_emergencies, uses_dc, esm_view \
                in rows:
            if not (first if p == 0 else reach[p] and reachable()):
                found = self._unreached(link)
                if found:
                    (lost_now if found == LOST else missing_now).append(p)
                quiet = False
                if exchange and reach[p] and self._line_powered[p]:
                    self._pass_silent(slave)
                continue
            if not link.present:
                if self._find(link):
                    recovered.append(p)
                self._watch(link)  # its state now (_find told a recovered one's found state)
                quiet = False
            if not exchange:
                continue
            exchange_frame(now_us)
            if not skip:
                self._serve(link)
                continue
            frames = take_emergencies()
            if not frames:  # _serve would do nothing (still.py)?
                state = slave.esm.state if esm_view else slave.al_state  # type: ignore
                pending = link.pending
                if pending is None:
                    idle = state is link.believed and (
                        state is (held if uses_dc else target) or now_us < link.next_try_us)
                else:  # _check would find the transition still under way
                    waited = now_us - link.requested_at_us
                    idle = waited < self.check_delay_us or (
                        state is not pending and waited < self.state_timeout_us
                        and not slave.al_status & AL_STATUS_ERROR_FLAG)
                    # ... unless the slave left on its own (startup._left_pending); the
                    # floor is 0 for INIT -> PREOP, the long wait of a FastCAT's scan
                    if idle and link.pending_floor and RANK.get(state, 0) < link.pending_floor \
                            and not slave.al_status & AL_STATUS_ERROR_FLAG:
                        idle = False
                if idle:
                    served += 1
                    if quiet and state is not watched[p]:  # type: ignore[index]
                        quiet = False
                    continue
            quiet = False
            self._serve(link, frames)
        skipped = self.skipped
        if served:
            skipped.serve += served
        if exchange and port_up:  # with link a frame goes out each cycle, answered or not
            self.frames += 1
        if lost_now or recovered or missing_now or self._links_moved:
            self._line_news(lost_now, recovered, missing_now)
        if quiet:
            # Each state read after its own frame and mailbox (no slave's frame moves
            # another slave), none served: the list _watch_states would make is ``watched``.
            skipped.watch += 1
        elif external or (cycle and not lost):  # states are read with the frames
            self._watch_states(skip)
        dc = self.dc
        if quiet and dc.state is _COMPENSATING and dc.fault is None and self._dc_links \
                and dc.compensate(self.rng):
            # Every DC slave present (quiet), link up, no fault, the deviation in the window:
            # compensate() did all measure() and trigger() would (dc.py).
            skipped.dc += 1
        else:
            self._step_dc(dt_us, quiet)
        if self._held:
            self._flush_log()
        if self.hooks.queued:
            self.hooks.run()

    def _watch_states(self, skip: bool = False) -> None:
        """Slave state changes, and the first OP of each slave / of the network (resync)."""
        states = [link.slave.al_state if link.present else None for link in self.links]
        if skip and states == self._watched:
            self.skipped.watch += 1  # a watch of the same states already did its work
            return
        for link in self.links:
            if link.present:
                self._watch(link)
        everyone = bool(self.links) and all(
            link.present and link.slave.al_state is AlState.OP for link in self.links)
        if everyone and not self.network_op:
            self.network_op = True
            self._event(Resync(self.now_us, self.device_id, position=-1))
        self._watched = states

    def _watch(self, link: SlaveLink, resync: bool = True) -> None:
        """A new state of ``link``'s slave is a ``slave_state`` event; its first OP since it
        was found, a Resync unless ``resync`` is False (the state a recovered slave is found
        in, before its restart from INIT)."""
        slave, now = link.slave, self.now_us
        state = slave.al_state
        if state is not link.seen:
            previous = link.seen
            before = previous.label if previous is not None else ""
            link.seen = state
            link.counters.state_changes += bool(before)
            self._event(SlaveStateChange(now, self.device_id, position=link.position,
                                         address=slave.station_address, from_state=before,
                                         to_state=state.label, code=slave.al_status_code))
            if state is AlState.SAFEOP and link.dc and (
                    previous is None or RANK.get(previous, 0) < RANK[AlState.SAFEOP]):
                # Up from INIT / PREOP (start-up, found again, resync): as the DC unit's
                # START_TIME, 100 ms after the DC slave is in SAFEOP. At start-up the unit's
                # own START_TIME comes no sooner; a slave that re-joins while DC stays
                # COMPENSATING has only this one (seed 003 WAITING_START_TIME).
                link.start_time_us = now + START_DELAY_US
        if resync and state is AlState.OP and not link.reached_op:
            link.reached_op = True
            self._event(Resync(now, self.device_id, position=link.position,
                               address=slave.station_address, slave=slave.device_id))

    def _step_dc(self, dt_us: int, quiet: bool = False) -> None:
        """The DC unit's cycle; ``quiet``: the step tried :meth:`DcUnit.compensate`, which
        drew the deviation and found it out of the window (trigger() counts it)."""
        dc = self.dc
        if quiet and dc.state is DcState.COMPENSATING and dc.fault is None and self._dc_links:
            dc_links = self._dc_links  # every one present (quiet)
        else:
            dc.measure(dt_us, self.rng)
            dc_links = [link for link in self._dc_links if link.present]
        # Only WAITING_START_TIME asks whether the DC slaves are ready (DcUnit.trigger): every
        # one in SAFEOP / OP but those whose start-up the master found refused (it retries
        # them; START_TIME does not wait for a broken slave, the others go on to OP).
        ready = False
        if dc.state is DcState.WAITING_START_TIME or not self.SKIP_STILL:
            synced = [link.slave.al_state in (AlState.SAFEOP, AlState.OP) for link in dc_links]
            ready = any(synced) and all(
                in_sync or link.stalled for in_sync, link in zip(synced, dc_links, strict=True))
        trigger = dc.trigger(self.now_us, self.link_up, len(dc_links), ready)
        if trigger is None:
            return
        deviation = dc.deviation_ns  # this cycle's, before a new SYNCHRONIZING resets it
        moved = dc.move(trigger, self.now_us)
        if moved is None:
            return
        before, after = moved
        self._event(StateChanged(self.now_us, self.device_id, from_state=before.value,
                                 to_state=after.value, machine=DC_MACHINE))
        if DcState.IDLE in moved:  # nothing measured yet, or nothing left to measure
            self._log(None, "dc_unmeasured", from_state=before.value, to_state=after.value,
                      window=dc.window_ns)
        else:
            self._log(None, "dc", from_state=before.value, to_state=after.value,
                      deviation=deviation, window=dc.window_ns)
        # Seed 003: the slaves do I/O from START_TIME on (COMPENSATING: "typically all slaves
        # are in OP state"); before it and out of sync the DC slaves stay in SAFEOP.
        self.dc_hold = after is not DcState.COMPENSATING
        if after is DcState.NOT_SYNCHRONIZED:
            for link in dc_links:  # seed 003: the slaves involved go to SAFE_OP
                if link.slave.al_state is AlState.OP and not self.external:
                    self._request(link, AlState.SAFEOP)
        elif after is DcState.COMPENSATING:
            # The held ones go on now (a sync error's refusal too); one refused below SAFEOP
            # (its configuration, not the clock: START_TIME did not wait for it) keeps its retry.
            for link in self.links:
                if not link.stalled or link.slave.al_state in (AlState.SAFEOP, AlState.OP):
                    link.next_try_us = min(link.next_try_us, self.now_us)

    # ---- events and the log -------------------------------------------------------------------
    def _event(self, event: Event) -> None:
        self.emit(event)
        self.hooks.queued.append(event)

    def _log(self, link: SlaveLink | None, message: str, **params: object) -> None:
        slave = link.slave if link is not None else None
        entry = Entry(self.now_us, message, params,
                      slave=slave.box_name if slave is not None else "",
                      address=slave.station_address if slave is not None else 0,
                      position=link.position if link is not None else -1)
        self.entries.append(entry)
        held = self._held
        if held and not same_group(held[0], entry):
            self._flush_log()
        if is_late(self.log_style, entry):
            held.append(entry)  # log_styles.arrange's order, line by line
        else:
            self._emit_row(entry)

    def _flush_log(self) -> None:
        held, self._held = self._held, []
        for entry in held:
            self._emit_row(entry)

    def _emit_row(self, entry: Entry) -> None:
        row = self._row(entry)
        self.log.append(row)
        self.emit(LogLine(entry.t_us, self.device_id, text=row["text"], port=self.port))

    def _row(self, entry: Entry) -> dict[str, Any]:
        return {"t": entry.t_us / 1_000_000, "port": self.port,
                "timestamp": twincat_timestamp(self.epoch, entry.t_us),
                "text": render(self.log_style, entry)}
