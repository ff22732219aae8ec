"""Two dashboards of the default rig built alike, to compare what each has sent, and a write
to viser that fails as viser 1.1.1's push() did off its loop (docs/dashboard.md "Threading").

What a browser is sent is the server's persistent message buffer: the last message of each
kind for each element. Built with the same uuids (viser draws them from ``uuid.uuid4``), the
two buffers differ only where one dashboard left something unsent.
"""

from __future__ import annotations

import contextlib
import itertools
import re
import uuid
from collections.abc import Callable, Iterator
from typing import Any

from served_dashboard import local_server

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.ui.dashboard import Dashboard

FAILURE = "deque mutated during iteration"


@contextlib.contextmanager
def twin(boot_steps: int) -> Iterator[Dashboard]:
    """The default rig stepped ``boot_steps`` times, its dashboard built with uuids counted
    from 0 (its twin gets the same ones) and its first frame drawn. The test ticks."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(boot_steps):
        rig.step()
    count = itertools.count(1)
    real = uuid.uuid4
    uuid.uuid4 = lambda: uuid.UUID(int=next(count))  # type: ignore[assignment]
    try:
        with local_server() as server:
            try:
                dashboard = Dashboard(server, Runtime(rig))
                dashboard.tick()
            finally:
                uuid.uuid4 = real  # type: ignore[assignment]
            yield dashboard
    finally:
        uuid.uuid4 = real  # type: ignore[assignment]


def sent(dashboard: Dashboard) -> dict[str, str]:
    """What a browser that connects now is sent: each element's last message of each kind.
    viser's GUI ``order`` counts elements over every server of the process: left out."""
    buffer = dashboard.server._websock_server._broadcast_buffer
    return {m.redundancy_key(): re.sub(r"'order': [0-9.]+", "", repr(m.as_serializable_dict([])))
            for m in buffer.message_from_id.values()}


def differing(a: Dashboard, b: Dashboard) -> list[str]:
    one, other = sent(a), sent(b)
    return sorted(k for k in one.keys() | other.keys() if one.get(k) != other.get(k))


def step(dashboard: Dashboard, steps: int) -> None:
    """The rig ``steps`` steps on and its frame published, as the simulation thread does."""
    for _ in range(steps):
        dashboard.runtime.rig.step()
    dashboard.runtime._publish()


@contextlib.contextmanager
def failing_write(dashboard: Dashboard, fails: Callable[[Any], bool]) -> Iterator[list[Any]]:
    """The first message ``fails(message)`` picks raises as viser 1.1.1's push() did: after the
    message is buffered (line 221 comes after the insert). Yields the failed messages."""
    buffer = dashboard.server._websock_server._broadcast_buffer
    push, failed = buffer.push, []

    def failing_push(message: Any) -> None:
        push(message)
        if not failed and fails(message):
            failed.append(message)
            raise RuntimeError(FAILURE)

    buffer.push = failing_push  # type: ignore[method-assign]
    try:
        yield failed
    finally:
        del buffer.push
