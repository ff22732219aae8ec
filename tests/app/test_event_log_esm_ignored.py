"""An AL control request a slave ignores (error flag set, bit 4 "Error Ind Ack" missing) is a
row of the State tab's event log, whatever the slave: before, a trainee's wire master writing
AL control without the bit saw nothing happen and no reason (devices/esm.py
``Esm.take_request``; docs/ethercat-wire.md "Error acknowledge").

The other log lines of the TRS-CAT and the CPX-E-EC stay out of that log, as before."""

from __future__ import annotations

import random

from app.ui.panels.event_log import event_message
from devices.cpx.device import CpxEEc
from devices.ethercat import AlState
from devices.events import LogLine
from devices.trscat.device import TrsCat


def refused_in_preop(slave: TrsCat | CpxEEc) -> int:
    """The slave after a refused PREOP -> OP (0x12, 0x0011); the time it got there."""
    now = 0
    for _ in range(3000):
        now += 1_000
        slave.step(now)
        slave.exchange_frame(now)
    slave.request_state(AlState.PREOP)
    slave.request_state(AlState.OP)
    assert (slave.al_status, slave.al_status_code) == (0x12, 0x0011)
    slave.drain_events()
    return now


def test_an_ignored_request_is_a_red_row_for_the_trscat_and_the_cpx() -> None:
    for slave, kind in ((TrsCat("trscat", random.Random(1), []), "trscat"),
                        (CpxEEc("cpx", random.Random(1), ["CPX-E-16DI"]), "cpx_e_ec")):
        refused_in_preop(slave)
        slave.request_state(AlState.SAFEOP)
        rows = [event_message(e, kind) for e in slave.drain_events()]
        rows = [r for r in rows if r is not None]
        assert len(rows) == 1, rows
        text, error = rows[0]
        assert "'SAFEOP'" in text and "ignored" in text and "0x0011 kept" in text
        assert error


def test_the_other_trscat_log_lines_stay_out() -> None:
    assert event_message(LogLine(0, "trscat", text="some line"), "trscat") is None
