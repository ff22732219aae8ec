"""The EtherCAT master's events and a scenario's focus as recording lines (docs/recording.md).

A support walkthrough replaying cable_pulled found them in the fallback form,
``slave_state: position=0, address=1001, from=, to=INIT, code=0x0000``, and every one at level
INFO: a CoE emergency the master read, a slave that fell with an AL status code, a lost slave.
The doc's levels say an emergency or a non-zero AL status code is a warning, whoever reports
it; a communication error is one too.
"""

from __future__ import annotations

import pytest

from app.recording import event_text
from devices.events import (
    CoeEmergency,
    CommError,
    Event,
    Focus,
    NetworkRecovery,
    Resync,
    SlaveStateChange,
)

LINES = [
    (SlaveStateChange(0, "master", position=0, address=1001, from_state="", to_state="INIT"),
     "slave 0 (1001): INIT", "INFO"),
    (SlaveStateChange(0, "master", position=0, address=1001, from_state="SAFEOP",
                      to_state="OP"), "slave 0 (1001): SAFEOP -> OP", "INFO"),
    (SlaveStateChange(0, "master", position=0, address=1001, from_state="OP",
                      to_state="PREOP", code=0x8204),
     "slave 0 (1001): OP -> PREOP, AL status code 0x8204", "WARN"),
    (CommError(0, "master", position=2, address=1003, reason="link_lost", count=1),
     "slave 2 (1003): communication error link_lost (count 1)", "WARN"),
    (CoeEmergency(0, "master", position=2, address=1003, code=0x3320, register=0x05,
                  data=bytes([0x1A, 2, 8, 0, 0])),
     "slave 2 (1003): CoE EMCY 0x3320 register 0x05 data [1A 02 08 00 00]", "WARN"),
    (CoeEmergency(0, "master", position=2, address=1003, code=0, register=0, data=bytes(5)),
     "slave 2 (1003): CoE EMCY 0x0000 register 0x00 data [00 00 00 00 00]", "INFO"),
    (Resync(0, "master", position=3, address=1004, slave="drive_ec-ecat"),
     "ECAT_Resync: slave 3 (1004) drive_ec-ecat", "INFO"),
    (Resync(0, "master", position=-1), "ECAT_Resync: the whole network", "INFO"),
    (NetworkRecovery(0, "master", positions=(2, 3)), "network recovery: slaves 2, 3", "INFO"),
    (Focus(0, "scenario", target="cpx:2"), "focus: cpx:2", "INFO"),
]


@pytest.mark.parametrize(("event", "text", "level"), LINES,
                         ids=[f"{e.kind}-{i}" for i, (e, _, _) in enumerate(LINES)])
def test_master_event_lines(event: Event, text: str, level: str) -> None:
    record = event.to_record()
    assert event_text.text(event, record) == text
    assert event_text.level(event, record) == level
