"""How the dashboard's callbacks talk to the simulation: check the role, enqueue, report.

A viser callback never touches a model. It hands a command to the runtime and returns; when
the simulation thread has applied it, the future's outcome comes back here. A refused command
(CommandError, SdoAbort) becomes a red notification on the browser that clicked, and only
there: the other browsers see the effect (or its absence) through the shared state panels.

Every command of a browser passes here, so this is where the roles are enforced (server side,
whatever the browser sends): a trainee connection's fault injection, rig reset or scenario
control is refused, logged (the runtime's event journal as a LogLine, and this module's
logger) and notified to that browser only (app/classroom/roles.py, docs/classroom.md). The
access of a served rig is installed per runtime (:func:`install_gate`), so every panel's
sender of that runtime applies it without being handed it.
"""

from __future__ import annotations

import logging
import threading
import weakref
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

import viser

from app.classroom.roles import Access, Operation, Role, instructor_only, operation_allowed
from app.runtime import Runtime
from app.targets import parse_target
from devices.device import CommandError
from devices.events import LogLine
from devices.od import SdoAbort

logger = logging.getLogger(__name__)

Done = Callable[[Any], None]
REFUSALS_DEVICE = "classroom"  # the device name of the refusal lines in the event journal


@dataclass(frozen=True)
class Sent:
    """One command a connection asked for, allowed or refused (exercises record them)."""

    client_id: int | None
    role: Role
    target: str
    action: str
    args: Mapping[str, Any] = field(default_factory=dict)
    refused: str = ""  # why, when refused


Observer = Callable[[Sent], None]


class Gate:
    """The access of one served runtime and who watches its commands."""

    def __init__(self, access: Access | None = None) -> None:
        self.access = access if access is not None else Access(None)
        self._observers: list[Observer] = []
        self._lock = threading.Lock()

    def observe(self, fn: Observer) -> None:
        with self._lock:
            self._observers.append(fn)

    def emit(self, sent: Sent) -> None:
        with self._lock:
            observers = list(self._observers)
        for fn in observers:
            try:
                fn(sent)
            except Exception:
                logger.exception("command observer failed")


_GATES: weakref.WeakKeyDictionary[Runtime, Gate] = weakref.WeakKeyDictionary()
_GATES_LOCK = threading.Lock()


def install_gate(runtime: Runtime, access: Access) -> Gate:
    """Serve ``runtime`` with ``access``; call before the dashboard is built."""
    with _GATES_LOCK:
        gate = _GATES.get(runtime)
        if gate is None:
            gate = _GATES[runtime] = Gate(access)
        else:
            gate.access = access
        return gate


def gate_for(runtime: Runtime) -> Gate:
    """The runtime's gate; an open one (everyone instructor) when none was installed."""
    with _GATES_LOCK:
        gate = _GATES.get(runtime)
        if gate is None:
            gate = _GATES[runtime] = Gate()
        return gate


# A refusal stays longer than a confirmation, but closes: toasts that stayed until clicked
# piled up over the 3D view's LEDs a trainee has to read (classroom review, session 11).
NOTE_S, ERROR_S = 4.0, 12.0


def notify(client: viser.ClientHandle | None, title: str, body: str, *,
           error: bool = False) -> None:
    if client is None:
        return
    try:
        client.add_notification(title, body, color="red" if error else "blue",
                                auto_close_seconds=ERROR_S if error else NOTE_S)
    except Exception:  # the browser may have gone away meanwhile
        logger.debug("could not notify client %s", getattr(client, "client_id", "?"),
                     exc_info=True)


def _confirmed(client: viser.ClientHandle | None, label: str, args: Mapping[str, Any],
               done: Done | None) -> Done:
    """``done``, after a blue note on ``client``'s page: what was applied, with what."""
    def then(result: Any) -> None:
        given = ", ".join(f"{k}={v}" for k, v in args.items()) or "no parameters"
        notify(client, f"{label} applied", given)
        if done is not None:
            done(result)
    return then


def _client_id(client: viser.ClientHandle | None) -> int | None:
    return None if client is None else int(client.client_id)


class CommandSender:
    def __init__(self, runtime: Runtime, gate: Gate | None = None) -> None:
        self._runtime = runtime
        self._gate = gate if gate is not None else gate_for(runtime)

    @property
    def gate(self) -> Gate:
        return self._gate

    def role(self, client: viser.ClientHandle | None) -> Role:
        return self._gate.access.role(_client_id(client))

    def send(self, client: viser.ClientHandle | None, target: str, action: str,
             args: dict[str, Any] | None = None, *, done: Done | None = None,
             confirm: bool = False) -> None:
        """Queue ``action`` on ``target``; errors go to ``client``, results to ``done``;
        ``confirm``: a short notification to ``client`` (its page only) once it is applied
        (the fault forms: an instructor's Apply said nothing unless refused)."""
        label = f"{target}: {action}"
        given = dict(args or {})
        role = self.role(client)
        if role is not Role.INSTRUCTOR:
            rule = instructor_only(self._kind(target), action, given)
            if rule is not None:
                self._refuse(client, role, target, action, given,
                             f"{action} {rule.why} (instructor only)")
                return
        self._gate.emit(Sent(_client_id(client), role, target, action, given))
        future = self._runtime.command(target, action, given)
        if confirm:
            done = _confirmed(client, label, given, done)
        future.add_done_callback(lambda f: self._report(client, label, f, done))

    def submit(self, client: viser.ClientHandle | None, label: str, fn: Callable[[], Any], *,
               done: Done | None = None, operation: Operation = Operation.OPERATE) -> None:
        """Run ``fn`` in the simulation thread (reads of the models, multi-step commands).

        ``operation`` says what ``fn`` does; a trainee may only run the operations that
        :func:`app.classroom.roles.operation_allowed` gives them. Fault injection is never a
        submitted function: it is a device action, checked by :meth:`send`."""
        if not self.allow(client, operation, label):
            return
        if client is not None:
            self._gate.emit(Sent(_client_id(client), self.role(client), label, operation.value))
        future = self._runtime.submit(fn)
        future.add_done_callback(lambda f: self._report(client, label, f, done))

    def allow(self, client: viser.ClientHandle | None, operation: Operation,
              label: str = "") -> bool:
        """Whether ``client`` may do ``operation`` now; a refusal is logged and notified."""
        role = self.role(client)
        if operation_allowed(role, operation):
            return True
        self._refuse(client, role, label or operation.value, operation.value, {},
                     f"{operation.value} is for the instructor")
        return False

    # ---- helpers ------------------------------------------------------------------------
    def _kind(self, target: str) -> str:
        try:
            device_id, _module = parse_target(target)
        except (CommandError, ValueError):
            return ""
        device = self._runtime.rig.devices.get(device_id)
        return str(getattr(device, "KIND", "")) if device is not None else ""

    def _refuse(self, client: viser.ClientHandle | None, role: Role, target: str, action: str,
                args: Mapping[str, Any], why: str) -> None:
        client_id = _client_id(client)
        text = f"refused from {role.value} connection {client_id}: {target}: {why}"
        logger.warning("%s", text)
        self._runtime.journal([LogLine(t_us=self._runtime.frame.t_us, device=REFUSALS_DEVICE,
                                       text=text)])
        self._gate.emit(Sent(client_id, role, target, action, dict(args), refused=why))
        notify(client, f"{target}: {action} refused", why, error=True)

    @staticmethod
    def _report(client: viser.ClientHandle | None, label: str, future: Future[Any],
                done: Done | None) -> None:
        exc = future.exception()
        if exc is None:
            if done is not None:
                try:
                    done(future.result())
                except Exception:
                    logger.exception("dashboard follow-up of %s failed", label)
            return
        if isinstance(exc, (CommandError, SdoAbort)):
            notify(client, f"{label} refused", str(exc), error=True)
            return
        logger.error("%s failed", label, exc_info=exc)
        notify(client, f"{label} failed", f"{type(exc).__name__}: {exc}", error=True)
