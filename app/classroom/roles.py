"""Who may do what on a served rig: the instructor and trainee roles, as data.

By default a rig is served on 127.0.0.1 and every browser is the instructor (a demo on one's
own machine). Served on any other address, the rig asks for an instructor token: a browser
that shows it is the instructor, any other browser is a trainee (docs/classroom.md).

A trainee sees and operates the rig. What a trainee may never do, whatever its browser sends:
make a fault (the rows of :data:`INSTRUCTOR_ONLY`), reset the rig, load or control a scenario,
run exercises (:data:`INSTRUCTOR_OPERATIONS`). The check is :func:`instructor_only`; the
server applies it to every command of a connection (``app.ui.commands.CommandSender``).
"""

from __future__ import annotations

import enum
import hmac
import ipaddress
import secrets
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

ANY_KIND = "*"


class Role(enum.Enum):
    INSTRUCTOR = "instructor"
    TRAINEE = "trainee"


@dataclass(frozen=True)
class Rule:
    """An action a trainee may not send to a device of ``kind``.

    ``when``: the arguments that make the action a fault (e.g. ``link`` with
    ``connected=False`` pulls the cable); the other direction is a repair, which a trainee may
    do (plug the cable back in). Empty: the action is instructor-only whatever its arguments.
    """

    kind: str
    action: str
    when: Mapping[str, Any] = field(default_factory=dict)
    why: str = ""

    def matches(self, kind: str, action: str, args: Mapping[str, Any]) -> bool:
        if self.kind not in (kind, ANY_KIND) or self.action != action:
            return False
        return all(args.get(name) == value for name, value in self.when.items())


def _rules(kind: str, *rows: tuple[str, dict[str, Any], str]) -> tuple[Rule, ...]:
    return tuple(Rule(kind, action, when, why) for action, when, why in rows)


FAULT = "makes a fault"
CAUSE = "hidden cause"
BREAK = "takes hardware away"

# Read from every model's ACTIONS table (devices/*/actions.py, devices/fastcat/rail.py and
# modules.py, devices/trscat/commands.py, devices/cpx/actions.py, devices/coe/actions.py,
# devices/master/, devices/canopen/node.py). Everything not listed is operation: inputs,
# CNF, object and register access, Reset fault, alarm reset, moves, NMT, resync.
INSTRUCTOR_ONLY: tuple[Rule, ...] = (
    # Any device kind: injecting or removing a hidden cause is the instructor's.
    *_rules(ANY_KIND, ("inject_fault", {}, CAUSE), ("clear_fault", {}, CAUSE),
            ("inject_alarm", {}, CAUSE), ("clear_alarm", {}, CAUSE)),
    *_rules("fastcat",
            ("power", {"on": False}, FAULT), ("link", {"connected": False}, FAULT),
            ("tbus_voltage", {"low": True}, FAULT), ("unplug", {}, BREAK),
            ("plug", {}, BREAK), ("swap", {}, BREAK), ("module_power", {"on": False}, FAULT),
            ("encoder_fault", {"active": True}, FAULT), ("output_short", {"active": True}, FAULT),
            ("pot_supply_short", {"active": True}, FAULT),
            ("ao_overload", {"active": True}, FAULT), ("calibrated", {"value": False}, FAULT),
            ("module_failure", {"active": True}, FAULT), ("set_encoder_ppr", {}, BREAK),
            ("wire_thermocouple", {}, BREAK)),
    *_rules("servo", ("power", {"on": False}, FAULT), ("jam_load", {"active": True}, FAULT)),
    # The line (seed 003): cables, slave supplies, lost frames, damaged cables and DC faults
    # are the instructor's; plugging back, powering on, repairing and clearing are repairs
    # (clearing the ESC error counters is the trainee's diagnosis, as a master's write).
    *_rules("master", ("pull_cable", {}, FAULT), ("power_slave", {"on": False}, FAULT),
            ("lose_frames", {}, FAULT), ("damage_cable", {}, FAULT),
            ("dc_fault", {}, FAULT)),
    *_rules("servo_ecat", ("link", {"connected": False}, FAULT)),
    *_rules("trscat",
            ("power", {"on": False}, FAULT), ("field_supply", {}, FAULT),
            ("link", {"connected": False}, FAULT), ("unplug", {}, BREAK), ("plug", {}, BREAK),
            ("set_load", {}, FAULT), ("drop_frames", {}, FAULT),
            ("lose_sync0", {"lost": True}, FAULT), ("frame_jitter", {}, FAULT),
            ("inject_sm_fault", {}, CAUSE), ("clear_sm_fault", {}, CAUSE)),
    *_rules("cpx_e_ec",
            ("power", {"on": False}, FAULT), ("supply", {}, FAULT),
            ("cable", {"connected": False}, FAULT), ("short_circuit", {"on": True}, FAULT),
            ("wire_break", {"on": True}, FAULT), ("replace_module", {}, BREAK)),
)


class Operation(enum.Enum):
    """What a browser can ask of the rig besides device actions."""

    SCENARIO = "scenario"  # load a scenario, play, pause, step, restart, speed
    RESET = "reset"  # the rig back to its factory state
    EXERCISE = "exercise"  # start, stop, read the scores of exercises
    RECORDING = "recording"  # download the session's recording (it shows every injection)
    OPERATE = "operate"  # several operating actions in one go (moves, NMT, SDO)


INSTRUCTOR_OPERATIONS = frozenset({Operation.SCENARIO, Operation.RESET, Operation.EXERCISE,
                                   Operation.RECORDING})


def instructor_only(kind: str, action: str, args: Mapping[str, Any] | None = None) -> Rule | None:
    """The rule that keeps ``action`` on a device of ``kind`` from trainees, or None."""
    given = dict(args or {})
    return next((r for r in INSTRUCTOR_ONLY if r.matches(kind, action, given)), None)


def makes_faults(kind: str, action: str) -> bool:
    """Whether ``action`` is instructor-only on a device of ``kind`` for some arguments: such
    an action belongs in a form a trainee does not see (the Line tab's "trscat faults")."""
    return any(r.kind in (kind, ANY_KIND) and r.action == action for r in INSTRUCTOR_ONLY)


def allowed(role: Role, kind: str, action: str, args: Mapping[str, Any] | None = None) -> bool:
    return role is Role.INSTRUCTOR or instructor_only(kind, action, args) is None


def operation_allowed(role: Role, operation: Operation) -> bool:
    return role is Role.INSTRUCTOR or operation not in INSTRUCTOR_OPERATIONS


def is_loopback(host: str) -> bool:
    """127.0.0.1, ::1, localhost: only this machine can connect."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def new_token() -> str:
    return secrets.token_urlsafe(12)


class Access:
    """The roles of one served rig's connections (client ids), thread-safe.

    ``token`` None: an open rig, every connection is the instructor. Otherwise a connection is
    a trainee until it shows the token (:meth:`present`).
    """

    def __init__(self, token: str | None = None) -> None:
        self.token = token
        self._instructors: set[int] = set()
        self._lock = threading.Lock()

    @classmethod
    def for_host(cls, host: str, token: str | None = None) -> Access:
        """Open on a loopback address unless a token is given; else a token is required
        (a generated one when none is given)."""
        if token is None and is_loopback(host):
            return cls(None)
        return cls(token or new_token())

    @property
    def open(self) -> bool:
        return self.token is None

    def role(self, client_id: int | None) -> Role:
        """``None``: the server itself (a scenario, a test) — always the instructor."""
        if self.token is None or client_id is None:
            return Role.INSTRUCTOR
        with self._lock:
            return Role.INSTRUCTOR if client_id in self._instructors else Role.TRAINEE

    def present(self, client_id: int, token: str) -> bool:
        """The connection shows ``token``: instructor when it is the right one."""
        if self.token is None:
            return True
        ok = hmac.compare_digest(token.strip().encode(), self.token.encode())
        if ok:
            with self._lock:
                self._instructors.add(client_id)
        return ok

    def forget(self, client_id: int) -> None:
        """The connection closed (a reconnect is a new connection that shows its token)."""
        with self._lock:
            self._instructors.discard(client_id)
