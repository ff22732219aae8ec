"""The master's per-slave view: what it needs of a slave, what it knows of it, the line.

A slave model is anything with the :class:`Slave` surface (the FastCAT, TRS-CAT, CPX-E-EC
and the drive's CoE side have it). The master keeps one :class:`SlaveLink` per line position:
the last confirmed state, the pending request, its diagnostic counters (seed 003: the
diagnostic structures per slave, readable by position or by physical address).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from devices.ethercat import AlState, describe_al_status_code
from devices.master.esc_errors import EscErrors
from devices.master.network import SlaveDescription

RANK = {AlState.INIT: 0, AlState.PREOP: 1, AlState.SAFEOP: 2, AlState.OP: 3}
TARGETS = ("INIT", "PREOP", "SAFEOP", "OP")
# ETG.1000.6 short names of the transitions (the ENI's <Transition> values).
TRANSITION_NAME: dict[tuple[AlState, AlState], str] = {
    (AlState.INIT, AlState.PREOP): "IP", (AlState.PREOP, AlState.SAFEOP): "PS",
    (AlState.SAFEOP, AlState.OP): "SO", (AlState.OP, AlState.SAFEOP): "OS",
    (AlState.SAFEOP, AlState.PREOP): "SP", (AlState.OP, AlState.PREOP): "OP",
    (AlState.PREOP, AlState.INIT): "PI", (AlState.SAFEOP, AlState.INIT): "SI",
    (AlState.OP, AlState.INIT): "OI"}


class Slave(Protocol):
    """What the master needs of a slave model."""

    box_name: str
    station_address: int
    device_id: str

    @property
    def al_state(self) -> AlState: ...
    @property
    def al_status(self) -> int: ...
    @property
    def al_status_code(self) -> int: ...
    def reachable(self) -> bool: ...
    # ack: AL control bit 4, "Error Ind Ack" (ETG.1000.6; devices/esm.py take_request)
    def request_state(self, target: AlState, ack: bool = False) -> None: ...
    def take_emergencies(self) -> list[bytes]: ...  # 8-byte frames (emergency_frame)
    def exchange_frame(self, now_us: int) -> None: ...
    # Quiet spans (docs/performance.md "Quiet spans"), optional: a slave without them keeps
    # its master, and so its rig, stepping one step at a time.
    # frames_quiet(): an exchange_frame now, and any number of them while the slave's own
    # steps stay quiet (quiet_until), would change nothing but what skip_frames sets.
    # skip_frames(n, last_us): as n such frames, the last at last_us, one per master cycle.
    # Optional: frame_passed(now_us), a frame crossed the slave while it does not answer
    # (powered, on the frames' path: its ESC forwards it; the drive's L/A follow it).
    def set_link(self, connected: bool, port: str = "in") -> None: ...
    def set_power(self, on: bool) -> None: ...
    def sdo_download(self, index: int, sub: int, data: bytes) -> None: ...
    def sdo_upload(self, index: int, sub: int) -> bytes: ...
    # Optional: describe_al_status_code(code) -> str, the slave's reading of its own
    # manufacturer AL status codes (al_status_code_text).


def al_status_code_text(slave: Slave, code: int) -> str:
    """A slave with manufacturer codes of its own reads them (optional
    ``describe_al_status_code``: the FastCAT's 0x80XX, seed 000 §7.7); else the ETG text."""
    own = getattr(slave, "describe_al_status_code", None)
    return str(own(code)) if own is not None else describe_al_status_code(code)


def next_state(current: AlState, target: AlState) -> AlState:
    """One ESM step from ``current`` toward ``target`` (down: straight there)."""
    if current is AlState.BOOT:  # BOOT is left only through INIT (ETG.1000.6)
        return AlState.INIT
    if RANK[target] <= RANK[current]:
        return target
    return next(s for s, r in RANK.items() if r == RANK[current] + 1)


@dataclass
class Counters:
    lost_frames: int = 0
    wkc_errors: int = 0
    emergencies: int = 0
    state_changes: int = 0

    def snapshot(self) -> dict[str, int]:
        return {"lost_frames": self.lost_frames, "wkc_errors": self.wkc_errors,
                "emergencies": self.emergencies, "state_changes": self.state_changes}


@dataclass
class SlaveLink:
    """The master's view of the slave at one line position."""

    slave: Slave
    position: int = 0
    description: SlaveDescription | None = None
    present: bool = False
    believed: AlState | None = None  # the state the master last confirmed
    pending: AlState | None = None  # a requested transition not checked yet
    pending_from: AlState = AlState.INIT
    # RANK of the lower of pending_from and pending: a slave read below it without the error
    # flag has left on its own while the request was under way (startup._left_pending).
    pending_floor: int = 0
    requested: AlState | None = None
    # Where the master was taking the slave when it made that request (its target, SAFEOP
    # for a DC slave DC holds): the "requested" of the §7.7 "state change aborted" line.
    goal: AlState | None = None
    requested_at_us: int = 0
    next_try_us: int = 0
    seen: AlState | None = None  # the state last reported in a SlaveStateChange
    reached_op: bool = False  # ECAT_Resync fired for this slave since it was (re)found
    lost_once: bool = False  # absent after having been present: its return is a recovery
    # Reported not found: it never answered since the master started (its first frames with
    # link on the port), as the description expects it (docs/ethercat-master.md).
    missing: bool = False
    diagnosis: str = ""  # the master's own finding (identity mismatch, init command failed)
    # Why it is lost, as the simulator knows it ("cable 2 pulled"): the instructor's view
    # only (the snapshot's ``injected``), never the diagnosis nor the log.
    injected_cause: str = ""
    identity_ok: bool | None = None  # None: not checked yet
    # Its last transition was refused or stopped by the master (retried): DC START_TIME does
    # not wait for it (docs/ethercat-master.md, distributed clocks).
    stalled: bool = False
    # A DC slave's own START_TIME (seed 003: "the first time the slaves implement I/O"), set
    # when it reaches SAFEOP from below; it is not asked for OP before it (startup._serve).
    start_time_us: int | None = None
    dc_derived: bool = False  # DC use when no network description is given
    counters: Counters = field(default_factory=Counters)
    # Its ESC's error counters 0x0300-0x0313 (esc_errors.py): the line's physics counts them.
    esc: EscErrors = field(default_factory=EscErrors)

    @property
    def dc(self) -> bool:
        return self.description.dc if self.description is not None else self.dc_derived

    def diagnostic(self) -> dict[str, Any]:
        """The per-slave diagnostic structure (seed 003), as the snapshot shows it: what the
        master reads, not the line's truth (a slave's supply, the cables: ``injected``)."""
        slave, present = self.slave, self.present
        code = slave.al_status_code if present else 0
        return {"position": self.position, "device": slave.device_id,
                "name": slave.box_name, "station_address": slave.station_address,
                "present": present,
                "state": slave.al_state.label if present else None,
                "requested": self.requested.label if self.requested else None,
                "al_status": slave.al_status if present else 0,
                "al_status_code": code,
                "al_status_text": al_status_code_text(slave, code),
                "diagnosis": self.diagnosis, "dc": self.dc,
                "counters": self.counters.snapshot(), "esc_errors": self.esc.snapshot()}
