"""What process B sends, applied to the models in the simulation thread (a mixin of
:class:`~app.ethercat_wire.bridge.WireBridge`).

AL control writes go to the master's ``external_request`` (the slave model decides), mailbox
messages to the slave's CoE server, SM2 images, sync manager and DC settings to its face,
frame counts to the slave's frame clock, statistics to ``external_stats``, ESC counter
batches and writes to the master's ``external_esc_counts`` / ``external_esc_write``, a
station address written to ``external_station_address``.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any

from app.ethercat_wire import messages as msg
from app.ethercat_wire.wire_slave import WireSlave
from devices.ethercat import AlState
from devices.sync_managers import SmSetup

if TYPE_CHECKING:
    from app.ethercat_wire.bridge import WireBridge

# The bridge's logger: one name for every line the wire's A side logs.
logger = logging.getLogger("app.ethercat_wire.bridge")

AL_STATE_MASK, AL_ACK = 0x0F, 0x10  # AL control: requested state, error acknowledge
AL_ID_REQUEST = 0x20  # AL control bit 5 (ETG.1000.6): the slave's face passes it on
MAX_AL_DEFER_US = 100_000  # an AL control waits at most this long for the frames before it


class FromWire:
    def _esc_counts(self: WireBridge, seq: int, counts: dict[int, bytes], run: int | None) -> None:
        self._esc_seq = seq
        add = getattr(self._master, "external_esc_counts", None)
        if add is None or run != self._run:  # the old run's: not the fresh model's (B dropped
            return                            # the batch too)
        for position, data in counts.items():
            s = self._slave(int(position))
            if s is not None:
                add(s.position, bytes(data))
                self._sync_esc_errors(s, counted=True)

    def _defer(self: WireBridge, message: tuple[Any, ...], now_us: int) -> bool:
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

    def _slave(self: WireBridge, position: int) -> WireSlave | None:
        if 0 <= position < len(self._slaves):
            return self._slaves[position]
        logger.info("EtherCAT wire: no slave at line position %s", position)
        return None

    def _handle(self: WireBridge, message: tuple[Any, ...], now_us: int) -> None:
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
        elif tag == msg.STATION:
            s = self._slave(message[1])
            if s is not None:
                s.station = int(message[2])
                self._give_station(s)
        elif tag in (msg.AL_CONTROL, msg.MAILBOX, msg.OUTPUTS, msg.DC, msg.SM):
            s = self._slave(message[1])
            if s is not None:
                self._for_slave(s, tag, message[2])
        else:
            logger.info("EtherCAT wire: unknown message %r", tag)

    def _for_slave(self: WireBridge, s: WireSlave, tag: str, payload: Any) -> None:
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

    def _give_station(self: WireBridge, s: WireSlave) -> None:
        """The station address the wire master wrote to the master model, which hands it to a
        slave that checks it (the FastCAT, seed 000 §6.19)."""
        give = getattr(self._master, "external_station_address", None)
        if give is not None and s.station is not None:
            give(s.position, s.station)

    def _al_control(self: WireBridge, s: WireSlave, value: int) -> None:
        ack = bool(value & AL_ACK)  # "Error Ind Ack": the slave model applies it
        try:
            state = AlState(value & AL_STATE_MASK)
        except ValueError:
            s.face.request_unknown_state(s.model, value & AL_STATE_MASK, ack)
        else:
            external = getattr(self._master, "external_request", None)
            if external is not None:
                external(s.position, state, ack)  # the master notes it, asks the slave model
            else:
                s.face.request_state(s.model, state, ack)
        s.face.request_id(s.model, bool(value & AL_ID_REQUEST))

    def _schedule_frames(self: WireBridge, counts: dict[int, int], now_us: int) -> None:
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

    def _stats(self: WireBridge, stats: dict[str, Any]) -> None:
        self.stats = dict(stats)
        for s in self._slaves:
            s.clock.master_cycle(float(stats.get("cycle_us", 0)))
        external = getattr(self._master, "external_stats", None)
        if external is not None and stats.get("run") == self._run:  # not the old run's counts
            external(frames=int(stats.get("frames", 0)),
                     lost_frames=int(stats.get("lost_frames", 0)),
                     cycle_us=round(float(stats.get("cycle_us", 0))),
                     wkc_errors=int(stats.get("wkc_errors", 0)))
