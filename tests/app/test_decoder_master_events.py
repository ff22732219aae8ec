"""Seed 003's events by name in the Codes tab: "the status change of slaves", "communication
errors", "emergency CoE messages", "distributed clock status variation", "resync events", "the
network recovery event" (and the PLC tasks ECAT_Notify / ECAT_Resync). Before, each read "no
code and no alarm name".
"""

from __future__ import annotations

import pytest

from app.decoder import MASTER, decode
from devices.master.hooks import SEED_EVENTS


@pytest.mark.parametrize(("query", "kind"), [
    ("network recovery", "network_recovery"),
    ("the network recovery event", "network_recovery"),
    ("resync", "resync"),
    ("Resync events", "resync"),
    ("ECAT_Resync", "resync"),
    ("the status change of slaves", "slave_state"),
    ("status change of slaves", "slave_state"),
    ("communication errors", "comm_error"),
    ("communication error", "comm_error"),
    ("emergency CoE messages", "coe_emergency"),
    ("distributed clock status variation", "dc_state"),
    ("dc_state", "dc_state"),
    ("slave_state", "slave_state"),
    ("network_recovery", "network_recovery"),
    ("'network recovery'", "network_recovery"),
])
def test_a_seed_003_event_by_name(query: str, kind: str) -> None:
    (m,) = decode(query)
    assert m.family == MASTER and m.source == "seed 003", m
    event = next(e for e in SEED_EVENTS if e.kind == kind)
    assert m.title == f'Master event "{event.name}"', m.title
    assert event.text in m.text and f"`{kind}`" in m.text, m.text


def test_the_names_are_seed_003s() -> None:
    assert [e.name for e in SEED_EVENTS] == [
        "the status change of slaves", "communication errors", "emergency CoE messages",
        "distributed clock status variation", "resync events", "the network recovery event"]


def test_the_recovery_reads_seed_003s_words() -> None:
    (m,) = decode("network recovery")
    assert "a reboot of EtherCAT communication to deal with a serious error case" in m.text


def test_ecat_notify_lists_every_event() -> None:
    (m,) = decode("ECAT_Notify")
    assert all(e.name in m.text for e in SEED_EVENTS), m.text
