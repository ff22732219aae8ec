"""What the instructor's page calls a connection (docs/classroom.md "Who did what").

Trainees give no name and viser's connection numbers mean nothing in the room, so a
connection is named after its role and the order in which it first acts (a command, allowed
or refused, or an answer): "trainee 1", "trainee 2", ...; on an open rig, where every page is
the instructor, "instructor 1", ... The name stays with the connection while the server runs;
a reloaded page is a new connection and gets the next number. Each trainee's page shows its
own name, so the instructor can ask who "trainee 2" is.
"""

from __future__ import annotations

import threading
from collections import Counter

from app.classroom.roles import Role


class ConnectionNames:
    def __init__(self) -> None:
        self._names: dict[int, str] = {}
        self._count: Counter[Role] = Counter()
        self._lock = threading.Lock()  # commands arrive on viser's threads

    def name(self, client_id: int | None, role: Role) -> str:
        """The connection's name, given at its first act."""
        if client_id is None:
            return "the server"  # an exercise file's injection, a test
        with self._lock:
            name = self._names.get(client_id)
            if name is None:
                self._count[role] += 1
                name = self._names[client_id] = f"{role.value} {self._count[role]}"
            return name

    def get(self, client_id: int | None) -> str | None:
        """The name given so far (None: the connection has not acted)."""
        with self._lock:
            return None if client_id is None else self._names.get(client_id)
