"""One served rig: its runtime, viser server, dashboard, access, recording and classroom.

``python -m app`` serves one or several of these in one process (``--rig a --rig b``,
``--rigs N``), each on its own port with its own runtime, clock and flash directory; tests
start them the same way. Protocol servers (Modbus, CAN) are the CLI's business.
"""

from __future__ import annotations

import logging
import socket
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import viser

from app.classroom.roles import Access
from app.rig import Rig
from app.runtime import Runtime
from app.ui.commands import CommandSender, install_gate
from app.ui.dashboard import Dashboard
from app.ui.panels.classroom import ClassroomPanel

if TYPE_CHECKING:  # rerun loads with a recorder only (app/recording/allocators.py)
    from app.recording import RigRecorder

logger = logging.getLogger(__name__)
WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})


@dataclass
class ServedRig:
    rig: Rig
    runtime: Runtime
    server: viser.ViserServer
    dashboard: Dashboard
    classroom: ClassroomPanel
    recorder: RigRecorder | None
    host: str
    port: int

    @property
    def url(self) -> str:
        # An IPv6 literal goes in brackets (RFC 3986 §3.2.2): http://::1:8080/ opens nothing
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    @property
    def shown_url(self) -> str:
        """The URL to hand to trainees: a wildcard bind address (0.0.0.0, ::) is no address
        a browser on another machine can open, so the machine's name stands in for it."""
        if self.host in WILDCARD_HOSTS:
            return f"http://{socket.gethostname()}:{self.port}/"
        return self.url

    @property
    def instructor_url(self) -> str:
        token = self.classroom.access.token
        return self.shown_url if token is None else f"{self.shown_url}?token={token}"

    def stop(self) -> None:
        self.classroom.stop()
        self.dashboard.stop()
        self.runtime.stop()
        self.server.stop()
        if self.recorder is not None:
            self.recorder.close()


def serve_rig(rig: Rig, access: Access, *, host: str = "127.0.0.1", port: int = 8080,
              speed: float = 1.0, record: str | Path | None = None,
              paused: bool = False, exercise_files: Sequence[Path] = (),
              scenarios: Path | None = None) -> ServedRig:
    """Start serving ``rig``: runtime, recorder (when ``record`` names a file), access gate,
    viser server, dashboard and classroom folder. ``paused``: the clock waits (tests);
    ``exercise_files``: the exercise files the instructor may play (app/classroom/
    exercise_file.py); ``scenarios``: the folder of ``--scenarios DIR`` (the picker's own)."""
    runtime = Runtime(rig, speed=speed)
    runtime.set_paused(paused)
    recorder = None
    if record is not None:
        # Here: importing app.recording sets rerun's allocator up for the process
        from app.recording import RigRecorder, attach_to_runtime

        recorder = RigRecorder(record)
        attach_to_runtime(runtime, recorder)
    install_gate(runtime, access)
    server = viser.ViserServer(host=host, port=port, verbose=False)
    dashboard = Dashboard(server, runtime, scenarios=scenarios)
    classroom = ClassroomPanel(server, runtime, CommandSender(runtime), recorder,
                               download_name=f"{_slug(rig.name)}.rrd",
                               player=getattr(dashboard, "scenario_player", None),
                               exercise_files=exercise_files,
                               instructor_widgets=dashboard.instructor_widgets(),
                               on_instructor=dashboard.instructor.promote)
    runtime.start()
    dashboard.start()
    return ServedRig(rig, runtime, server, dashboard, classroom, recorder, host,
                     server.get_port())


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "-" for c in name).strip("-") or "rig"
