"""How the dashboard's callbacks talk to the simulation: enqueue, then report to the clicker.

A viser callback never touches a model. It hands a command to the runtime and returns; when
the simulation thread has applied it, the future's outcome comes back here. A refused command
(CommandError, SdoAbort) becomes a red notification on the browser that clicked, and only
there: the other browsers see the effect (or its absence) through the shared state panels.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

import viser

from app.runtime import Runtime
from devices.device import CommandError
from devices.od import SdoAbort

logger = logging.getLogger(__name__)

Done = Callable[[Any], None]


def notify(client: viser.ClientHandle | None, title: str, body: str, *,
           error: bool = False) -> None:
    if client is None:
        return
    try:
        client.add_notification(title, body, color="red" if error else "blue",
                                auto_close_seconds=None if error else 4.0)
    except Exception:  # the browser may have gone away meanwhile
        logger.debug("could not notify client %s", getattr(client, "client_id", "?"),
                     exc_info=True)


class CommandSender:
    def __init__(self, runtime: Runtime) -> None:
        self._runtime = runtime

    def send(self, client: viser.ClientHandle | None, target: str, action: str,
             args: dict[str, Any] | None = None, *, done: Done | None = None) -> None:
        """Queue ``action`` on ``target``; errors go to ``client``, results to ``done``."""
        label = f"{target}: {action}"
        future = self._runtime.command(target, action, args)
        future.add_done_callback(lambda f: self._report(client, label, f, done))

    def submit(self, client: viser.ClientHandle | None, label: str, fn: Callable[[], Any], *,
               done: Done | None = None) -> None:
        """Run ``fn`` in the simulation thread (reads of the models, multi-step commands)."""
        future = self._runtime.submit(fn)
        future.add_done_callback(lambda f: self._report(client, label, f, done))

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
