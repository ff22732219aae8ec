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

from devices.events import (
    CoeEmergency,
    CommError,
    Event,
    NetworkRecovery,
    Resync,
    SlaveStateChange,
)

logger = logging.getLogger(__name__)

Callback = Callable[[Event], None]


@dataclass(frozen=True)
class SeedEvent:
    """One of the events seed 003 lists ("Events can typically be: ..."): ``name`` exactly as
    the seed writes it, ``kind`` the event's name in FieldRig's event log and ``[[on]]`` tables,
    ``text`` what it is, in the seed's words where it gives some; ``logged`` how the event
    log writes it when that is not ``kind``."""

    name: str
    kind: str
    text: str
    logged: str = ""


DC_STATE_KIND = "dc_state"  # [[on]] event = "dc_state"; the log's `state` of machine `dc`
SEED_EVENTS: tuple[SeedEvent, ...] = (
    SeedEvent("the status change of slaves", SlaveStateChange.kind,
              "a slave's state changed (INIT, PREOP, SAFEOP, OP), with the AL status code it "
              "showed"),
    SeedEvent("communication errors", CommError.kind,
              "frames of a slave lost, its link lost, a slave of the description never found, "
              "or its identity check or an init command failed"),
    SeedEvent("emergency CoE messages", CoeEmergency.kind,
              "a CoE emergency the master read from a slave's mailbox: error code, error "
              "register, five data bytes"),
    SeedEvent("distributed clock status variation", DC_STATE_KIND,
              "the master's distributed-clock management changed phase (IDLE, SYNCHRONIZING, "
              "WAITING_START_TIME, COMPENSATING, NOT_SYNCHRONIZED)",
              logged="state (machine dc)"),
    SeedEvent("resync events", Resync.kind,
              "they occur when the slaves or the entire network are ready to go into "
              "operating mode; the ECAT_Resync task is invoked the first time a node or the "
              "whole network goes into operating mode, so that the PLC programmer can "
              "configure slaves by sending and receiving SDOs"),
    SeedEvent("the network recovery event", NetworkRecovery.kind,
              "it indicates a reboot of EtherCAT communication to deal with a serious error "
              "case: the master restarts the slaves it had lost"),
)
NOTIFY_TEXT = ("the special PLC task run at every event, after the diagnostic structures are "
               "updated and the registered plugins' callbacks invoked; it reads the updated "
               "structures")


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
