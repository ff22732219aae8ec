"""The master's callbacks (seed 003): ECAT_Notify and ECAT_Resync.

Seed 003: an event updates the diagnostic structures, then invokes the registered plugins'
callbacks and the PLC task ECAT_Notify (which reads the updated structures); ECAT_Resync runs
the first time a node or the whole network goes to OP, so that the PLC can configure slaves
with SDOs. Here both are lists of callables, run in registration order at the end of the
master's step (every structure is updated by then), in simulated time: deterministic.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

from devices.events import Event, Resync

logger = logging.getLogger(__name__)

Callback = Callable[[Event], None]


@dataclass
class Hooks:
    notify: list[Callback] = field(default_factory=list)
    resync: list[Callback] = field(default_factory=list)
    queued: list[Event] = field(default_factory=list)

    def run(self) -> None:
        """Call the callbacks for the events queued during this step, in order."""
        events, self.queued = self.queued, []
        for event in events:
            for callback in self.notify:
                callback(event)
            if isinstance(event, Resync):
                for callback in self.resync:
                    callback(event)
