"""Typed events that device models emit, stamped with simulated time.

Every event renders to one JSON-able record with the stable schema of the scenario runner:
``{"t": <simulated seconds>, "device": <id>, "event": <kind>, ...}``. Keys beyond those three
belong to the event kind and are part of the public schema (issue 2 §4): change them only with
a migration note.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any, ClassVar

US_PER_S = 1_000_000


def fmt_hex(value: int, width: int) -> str:
    """``0xFF00`` style: upper-case digits, fixed width, as TwinCAT and the seeds print them."""
    return f"0x{value:0{width}X}"


def fmt_bytes(data: bytes) -> str:
    """Bytes in transmission order, byte 0 first, two upper-case hex digits each."""
    return " ".join(f"{b:02X}" for b in data)


# Slots: the runtime journals the last 20,000 events (app/runtime.py JOURNAL_LENGTH), and a
# __dict__ per event was most of that memory (issue 7 soak; docs/hardening.md). A slotted
# dataclass is a new class, so its methods cannot use a bare super() (Python < 3.14): the
# slave events call SlaveEvent.fields explicitly.
@dataclass(frozen=True, slots=True)
class Event:
    t_us: int
    device: str
    kind: ClassVar[str] = "event"

    def fields(self) -> dict[str, Any]:
        return {}

    def to_record(self) -> dict[str, Any]:
        return {"t": self.t_us / US_PER_S, "device": self.device, "event": self.kind,
                **self.fields()}


@dataclass(frozen=True, slots=True)
class StateChanged(Event):
    """A state machine moved (EtherCAT ESM, CiA 402, NMT, DC, ...)."""

    from_state: str = ""
    to_state: str = ""
    machine: str = ""  # empty for the main machine: the ESM, a drive's CiA 402 (architecture.md)
    kind: ClassVar[str] = "state"

    def fields(self) -> dict[str, Any]:
        out: dict[str, Any] = {"from": self.from_state, "to": self.to_state}
        if self.machine:
            out["machine"] = self.machine
        return out


@dataclass(frozen=True, slots=True)
class EmergencySent(Event):
    """A CoE / CANopen emergency: error code, error register, manufacturer bytes."""

    code: int = 0
    register: int = 0
    data: bytes = b""
    kind: ClassVar[str] = "emergency"

    def fields(self) -> dict[str, Any]:
        return {"code": fmt_hex(self.code, 4), "register": fmt_hex(self.register, 2),
                "data": fmt_bytes(self.data)}


@dataclass(frozen=True, slots=True)
class AlStatusChanged(Event):
    """The AL status code register (0x134) took a new value."""

    code: int = 0
    kind: ClassVar[str] = "al_status"

    def fields(self) -> dict[str, Any]:
        return {"code": fmt_hex(self.code, 4)}


@dataclass(frozen=True, slots=True)
class LedChanged(Event):
    """An LED changed pattern (ETG.1300 names, see devices.leds.LedPattern)."""

    led: str = ""
    pattern: str = ""
    color: str = ""  # only for multi-colour LEDs (e.g. the CPX-E-EC's green/orange Run)
    kind: ClassVar[str] = "led"

    def fields(self) -> dict[str, Any]:
        out: dict[str, Any] = {"led": self.led, "pattern": self.pattern}
        if self.color:
            out["color"] = self.color
        return out


@dataclass(frozen=True, slots=True)
class AlarmChanged(Event):
    """A device alarm was raised or cleared (code as the device's manual numbers it)."""

    code: str = ""
    name: str = ""
    active: bool = True
    module: int = 0
    kind: ClassVar[str] = "alarm"

    def fields(self) -> dict[str, Any]:
        out: dict[str, Any] = {"code": self.code, "name": self.name, "active": self.active}
        if self.module:
            out["module"] = self.module
        return out


@dataclass(frozen=True, slots=True)
class LogLine(Event):
    """A line of a logger (the EtherCAT master's, in TwinCAT style, or a device's own)."""

    text: str = ""
    port: int = 0
    kind: ClassVar[str] = "log"

    def fields(self) -> dict[str, Any]:
        out: dict[str, Any] = {"text": self.text}
        if self.port:
            out["port"] = self.port
        return out


@dataclass(frozen=True, slots=True)
class EsmLogLine(LogLine):
    """A slave ESM's own line (devices/esm.py): an AL control request it ignored. The same kind
    and record as :class:`LogLine`; its own class so a view shows it for every slave kind."""


@dataclass(frozen=True, slots=True)
class Caption(Event):
    text: str = ""
    kind: ClassVar[str] = "caption"

    def fields(self) -> dict[str, Any]:
        return {"text": self.text}


@dataclass(frozen=True, slots=True)
class Checkpoint(Event):
    name: str = ""
    kind: ClassVar[str] = "checkpoint"

    def fields(self) -> dict[str, Any]:
        return {"name": self.name}


@dataclass(frozen=True, slots=True)
class Focus(Event):
    """A scenario points the audience at a device (``"trscat"``) or one of its modules
    (``"fastcat:2"``): the dashboard moves the camera there."""

    target: str = ""
    kind: ClassVar[str] = "focus"

    def fields(self) -> dict[str, Any]:
        return {"target": self.target}


@dataclass(frozen=True, slots=True)
class ValueRead(Event):
    """Answer of a scenario ``read`` step (an object or register read)."""

    address: str = ""
    value: Any = None
    kind: ClassVar[str] = "read"

    def fields(self) -> dict[str, Any]:
        value = self.value
        if isinstance(value, bytes | bytearray):  # an OCTET_STRING object: JSON-able hex
            value = fmt_bytes(value)
        out: dict[str, Any] = {"address": self.address, "value": value}
        if isinstance(self.value, int) and not isinstance(self.value, bool):
            out["hex"] = f"0x{self.value & 0xFFFFFFFF:08X}"
        return out


@dataclass(frozen=True, slots=True)
class SlaveEvent(Event):
    """Base of the EtherCAT master's events about one slave (seed 003 "events"): the slave's
    position on the line (from 0) and its physical (station) address."""

    position: int = 0
    address: int = 0

    def fields(self) -> dict[str, Any]:
        return {"position": self.position, "address": self.address}


@dataclass(frozen=True, slots=True)
class SlaveStateChange(SlaveEvent):
    """The master saw a slave's ESM state change (requested or not)."""

    from_state: str = ""
    to_state: str = ""
    code: int = 0  # the AL status code the slave showed with the new state
    kind: ClassVar[str] = "slave_state"

    def fields(self) -> dict[str, Any]:
        return {**SlaveEvent.fields(self), "from": self.from_state, "to": self.to_state,
                "code": fmt_hex(self.code, 4)}


@dataclass(frozen=True, slots=True)
class CommError(SlaveEvent):
    """A communication error the master saw on a slave: ``reason`` is ``lost_frames``,
    ``link_lost`` (the slave is no longer on the line), ``not_found`` (expected, it has not
    answered since the master started), ``identity`` (0x1018 is not the
    description's, or could not be read) or ``init_command`` (an init command's SDO was refused)."""

    reason: str = ""
    count: int = 0
    kind: ClassVar[str] = "comm_error"

    def fields(self) -> dict[str, Any]:
        return {**SlaveEvent.fields(self), "reason": self.reason, "count": self.count}


@dataclass(frozen=True, slots=True)
class CoeEmergency(SlaveEvent):
    """A CoE emergency the master read from a slave's mailbox."""

    code: int = 0
    register: int = 0
    data: bytes = b""
    kind: ClassVar[str] = "coe_emergency"

    def fields(self) -> dict[str, Any]:
        return {**SlaveEvent.fields(self), "code": fmt_hex(self.code, 4),
                "register": fmt_hex(self.register, 2), "data": fmt_bytes(self.data)}


@dataclass(frozen=True, slots=True)
class Resync(Event):
    """Seed 003 ECAT_Resync: a slave (``position`` >= 0) or the whole network
    (``position`` -1) reached OP for the first time since start-up or a recovery."""

    position: int = -1
    address: int = 0
    slave: str = ""  # the slave's device id; empty for the whole network
    kind: ClassVar[str] = "resync"

    def fields(self) -> dict[str, Any]:
        out: dict[str, Any] = {"position": self.position}
        if self.position >= 0:
            out.update(address=self.address, slave=self.slave)
        return out


@dataclass(frozen=True, slots=True)
class NetworkRecovery(Event):
    """Seed 003 "network recovery": the master restarts communication with slaves it had
    lost (a re-plugged cable, a slave powered again); ``positions`` are the recovered ones."""

    positions: tuple[int, ...] = ()
    kind: ClassVar[str] = "network_recovery"

    def fields(self) -> dict[str, Any]:
        return {"positions": list(self.positions)}


# Every put leaves a fresh number in LAST_PUT[0]: a rig looks into its devices' queues only
# when the number moved since its last look (app/rig.py Rig._collect; a look at eleven
# devices' queues cost ~4 % of a moving step, docs/performance.md "Session 22"). One number
# for every queue of the process: a put into another rig's queue costs a needless look, never a
# missed one. Each number is new (next() of a count is one C call, atomic under the GIL), so a
# put is never mistaken for one a look has seen, whatever thread steps which rig.
_PUTS = itertools.count(1)
LAST_PUT = [0]


@dataclass
class EventQueue:
    """The events a model emitted since the runtime last drained them."""

    items: list[Event] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.items:
            LAST_PUT[0] = next(_PUTS)

    def put(self, event: Event) -> None:
        self.items.append(event)
        LAST_PUT[0] = next(_PUTS)

    def drain(self) -> list[Event]:
        out, self.items = self.items, []
        return out
