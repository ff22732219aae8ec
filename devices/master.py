"""The minimal built-in EtherCAT master: brings its slaves to OP and logs like TwinCAT.

A stand-in until the full master (a later issue): it assigns station addresses (1001, 1002,
... as TwinCAT does), walks each slave INIT -> PREOP -> SAFEOP -> OP, reads the emergencies
from the slaves' mailboxes, notices a slave that left OP on its own and tries to bring it back
every ``retry_interval_us``. Its logger writes the lines of seed 000 §7.1 / §7.7 with the
TwinCAT port (65535) and timestamp ("12/11/2019 14.51.30 421 ms" = epoch + simulated time).

Timing: a requested transition is checked ``check_delay_us`` after the request. The default,
141 ms, is the gap the §7.7 log shows between "abnormal state change" (280 ms) and "'PREOP to
SAFEOP' failed!" (421 ms). INIT -> PREOP waits for the slave's internal-bus scan (seconds) up
to ``state_timeout_us``. See docs/fastcat-coupler.md.
"""

from __future__ import annotations

import collections
import datetime as dt
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

from devices.device import Action, DeviceModel, Param
from devices.ethercat import AL_STATUS_ERROR_FLAG, AlState, parse_emergency_frame
from devices.events import LogLine

TWINCAT_PORT = 65535  # seed 000 §7.1 / §7.7: "Server (porta) (65535)"
FIRST_STATION_ADDRESS = 1001  # §7.1 / §7.7: "'Box 1 (FastCAT)' (1001)"
STATE_CHECK_DELAY_US = 141_000  # §7.7 log: 14.51.30 280 ms -> 421 ms
STATE_TIMEOUT_US = 10_000_000  # covers a 16-module scan (§3: "qualche secondo")
LOG_LENGTH = 500
DEFAULT_EPOCH = dt.datetime(2019, 11, 12, 14, 51, 30)  # the §7.7 log's date
EMERGENCY_TEXT = "CoE - Emergency (Hex: {code:04x}, {register:02x}, {data}')."

_RANK = {AlState.INIT: 0, AlState.PREOP: 1, AlState.SAFEOP: 2, AlState.OP: 3}
TARGETS = ("INIT", "PREOP", "SAFEOP", "OP")


class Slave(Protocol):
    """What the master needs of a slave model (devices.fastcat.coupler.FastCat has it)."""

    box_name: str
    station_address: int

    @property
    def al_state(self) -> AlState: ...
    @property
    def al_status(self) -> int: ...
    @property
    def al_status_code(self) -> int: ...
    def reachable(self) -> bool: ...
    def request_state(self, target: AlState) -> None: ...
    def take_emergencies(self) -> list[bytes]: ...  # 8-byte frames (emergency_frame)
    def exchange_frame(self, now_us: int) -> None: ...


@dataclass
class SlaveLink:
    """The master's view of one slave."""

    slave: Slave
    present: bool = False
    believed: AlState | None = None  # the state the master last confirmed
    pending: AlState | None = None  # a requested transition not checked yet
    pending_from: AlState = AlState.INIT
    requested: AlState | None = None
    requested_at_us: int = 0
    next_try_us: int = 0


def next_state(current: AlState, target: AlState) -> AlState:
    """One ESM step from ``current`` toward ``target`` (down: straight there)."""
    if current is AlState.BOOT:  # BOOT is left only through INIT (ETG.1000.6)
        return AlState.INIT
    if _RANK[target] <= _RANK[current]:
        return target
    return next(s for s, r in _RANK.items() if r == _RANK[current] + 1)


def twincat_timestamp(epoch: dt.datetime, t_us: int) -> str:
    """``12/11/2019 14.51.30 421 ms``: the TwinCAT logger's format (seed 000 §7.1, §7.7)."""
    at = epoch + dt.timedelta(microseconds=t_us)
    return f"{at:%d/%m/%Y %H.%M.%S} {at.microsecond // 1000:03d} ms"


class EtherCatMaster(DeviceModel):
    KIND = "master"
    ACTIONS: ClassVar[Mapping[str, Action]] = {a.name: a for a in (
        Action("resync", "Take every slave through INIT and back to the target state (a "
                         "resync resets the FastCAT alarms whose cause is gone, seed 000 §7)"),
        Action("set_target", "The state the master brings its slaves to",
               (Param("state", str, choices=TARGETS),)),
    )}

    def __init__(self, device_id: str = "master", rng: random.Random | None = None,
                 slaves: Sequence[Slave] = (), retry_interval_us: int = 2_000_000,
                 port: int = TWINCAT_PORT, epoch: dt.datetime = DEFAULT_EPOCH,
                 check_delay_us: int = STATE_CHECK_DELAY_US,
                 state_timeout_us: int = STATE_TIMEOUT_US) -> None:
        super().__init__(device_id=device_id, rng=rng or random.Random(0))
        self.links = [SlaveLink(s) for s in slaves]
        for i, link in enumerate(self.links):
            link.slave.station_address = FIRST_STATION_ADDRESS + i
        self.retry_interval_us = retry_interval_us
        self.port = port
        self.epoch = epoch
        self.check_delay_us = check_delay_us
        self.state_timeout_us = state_timeout_us
        self.target = AlState.OP
        self.log: collections.deque[dict[str, Any]] = collections.deque(maxlen=LOG_LENGTH)

    # ---- commands ---------------------------------------------------------------------------
    def cmd_resync(self) -> None:
        for link in self.links:
            if link.present:
                self._request(link, AlState.INIT)

    def cmd_set_target(self, state: str) -> None:
        self.target = AlState[state]
        for link in self.links:
            link.next_try_us = self.now_us

    # ---- stepping ---------------------------------------------------------------------------
    def step(self, now_us: int) -> None:
        super().step(now_us)
        for link in self.links:
            self._serve(link)

    def _serve(self, link: SlaveLink) -> None:
        slave, now = link.slave, self.now_us
        if not slave.reachable():
            link.present, link.believed, link.pending = False, None, None
            return
        if not link.present:  # found (again): start from whatever state it is in
            link.present, link.believed, link.next_try_us = True, slave.al_state, now
        slave.exchange_frame(now)
        for frame in slave.take_emergencies():
            code, register, data = parse_emergency_frame(frame)
            self._log(slave, EMERGENCY_TEXT.format(code=code, register=register,
                                                   data=" ".join(f"{b:02x}" for b in data)))
        if link.pending is not None:
            self._check(link)
            return
        state = slave.al_state
        if state is not link.believed:
            self._log(slave, f"abnormal state change (from '{link.believed.label}' to "
                             f"'{state.label}') with code 0x{slave.al_status_code:04X}. "
                             f"Try to go back to '{self.target.label}'...")
            link.believed, link.next_try_us = state, now
        if state is not self.target and now >= link.next_try_us:
            self._request(link, next_state(state, self.target))

    def _request(self, link: SlaveLink, target: AlState) -> None:
        link.pending, link.pending_from = target, link.slave.al_state
        link.requested, link.requested_at_us = target, self.now_us
        link.slave.request_state(target)

    def _check(self, link: SlaveLink) -> None:
        slave, now = link.slave, self.now_us
        waited = now - link.requested_at_us
        if waited < self.check_delay_us:
            return
        state, target = slave.al_state, link.pending
        assert target is not None
        if state is target:
            link.believed, link.pending, link.next_try_us = state, None, now
            return
        if not slave.al_status & AL_STATUS_ERROR_FLAG and waited < self.state_timeout_us:
            return  # still busy (INIT -> PREOP waits for the internal-bus scan)
        self._log(slave, f"'{link.pending_from.label} to {target.label}' failed! Error: 'check "
                         f"device state for {target.label}'. AL Status "
                         f"'0x{slave.al_status:04X}' read and '0x{int(target):04X}' expected. "
                         f"AL Status Code '0x{slave.al_status_code:04X}'")
        self._log(slave, f"state change aborted (requested '{self.target.label}', back to "
                         f"'{state.label}').")
        link.believed, link.pending = state, None
        link.next_try_us = now + self.retry_interval_us

    def _log(self, slave: Slave, message: str) -> None:
        text = f"'{slave.box_name}' ({slave.station_address}): {message}"
        self.log.append({"t": self.now_us / 1_000_000, "port": self.port,
                         "timestamp": twincat_timestamp(self.epoch, self.now_us),
                         "text": text})
        self.emit(LogLine(self.now_us, self.device_id, text=text, port=self.port))

    # ---- view -------------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        return {"kind": self.KIND, "id": self.device_id, "target": self.target.label,
                "slaves": [self._slave_snapshot(link) for link in self.links],
                "log": list(self.log)}

    @staticmethod
    def _slave_snapshot(link: SlaveLink) -> dict[str, Any]:
        slave = link.slave
        present = slave.reachable()
        return {"name": slave.box_name, "station_address": slave.station_address,
                "present": present, "state": slave.al_state.label if present else None,
                "requested": link.requested.label if link.requested else None,
                "al_status": slave.al_status if present else 0,
                "al_status_code": slave.al_status_code if present else 0}
