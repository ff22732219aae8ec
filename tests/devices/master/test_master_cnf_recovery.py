"""A slave that falls below a pending request on its own (seed 003 "the status change of
slaves"; seed 000 §2 CNF): the master reads it at once as an abnormal state change and starts
it again, instead of waiting out its state timeout (docs/ethercat-master.md, start-up 5).

The FastCAT's CNF procedure drops its ESM to INIT on release and rescans its internal bus
(seed 000 §2). Released while the master walks the coupler up after power-on (PREOP -> SAFEOP
or SAFEOP -> OP pending), the coupler is back in OP within the scan and the master's usual
steps; before, the master waited its 10 s timeout and the retry interval, the coupler back in
OP some 9 s after its scan ended.
"""

from __future__ import annotations

import pytest
from line_bench import LINE_RIG, US, records

from app.rig import Rig
from app.rig_config import build_rig, load_rig_spec
from devices.ethercat import AlState
from devices.events import Event
from devices.master import EtherCatMaster

MS = 1000


def _master(rig: Rig) -> EtherCatMaster:
    master = rig.devices["master"]
    assert isinstance(master, EtherCatMaster)
    return master


def _texts(events: list[Event], t_from: float = 0.0) -> list[tuple[float, str]]:
    return [(r["t"], r["text"]) for r in records(events, "log", "master") if r["t"] >= t_from]


@pytest.mark.parametrize("skip_still", [True, False])
@pytest.mark.parametrize("pending", ["SAFEOP", "OP"])
def test_cnf_released_with_a_request_pending_restarts_the_coupler_at_once(
        pending: str, skip_still: bool) -> None:
    rig = build_rig(load_rig_spec(LINE_RIG), state_dir=None)
    master, fastcat = _master(rig), rig.devices["fastcat"]
    master.SKIP_STILL = skip_still
    link = master.links[0]
    rig.apply("fastcat", "press_cnf", {})
    events: list[Event] = []
    while link.pending is not AlState[pending]:  # the master walks the coupler up
        events += rig.step()
        assert rig.clock.now_us < 5 * US
    events += rig.run_until(rig.clock.now_us + 20 * MS)  # inside the 141 ms check delay
    assert link.pending is AlState[pending] and fastcat.al_state is AlState[pending]
    released_us = rig.clock.now_us
    rig.apply("fastcat", "release_cnf", {})  # held > 3 s (seed 000 §2)
    events += rig.run_until(released_us + 2 * MS)
    assert fastcat.al_state is AlState.INIT and fastcat.scan is not None
    # Read at the master's next cycle: the line, the event, and the way back requested (the
    # coupler holds INIT -> PREOP until its scan ends).
    t = (released_us + MS) / US
    assert _texts(events, t) == [
        (t, f"'Box 1 (FastCAT)' (1001): abnormal state change (from '{pending}' to 'INIT') "
            "with code 0x0000. Try to go back to 'OP'...")]
    assert [(r["t"], r["from"], r["to"]) for r in records(events, "slave_state", "master")
            if r["position"] == 0 and r["t"] >= t] == [(t, pending, "INIT")]
    assert (link.pending, link.requested) == (AlState.PREOP, AlState.PREOP)
    scan = fastcat.scan
    assert (scan.cnf, scan.start_us) == (True, released_us)
    scan_end_us = scan.end_us  # reset, scan, configuration stored
    events += rig.run_until(scan_end_us + US)
    op = [r["t"] for r in records(events, "slave_state", "master")
          if r["position"] == 0 and r["to"] == "OP" and r["t"] > t]
    # PREOP at the scan's end, SAFEOP and OP each one check delay (141 ms) later.
    assert op and op[0] * US - scan_end_us <= 300 * MS, (op, scan_end_us)
    assert fastcat.al_state is AlState.OP
    assert not [text for _t, text in _texts(events, t) if "failed" in text or "aborted" in text]
    # It left SAFEOP / OP on its own: its process data stopped answering once.
    assert master.slave_at(0)["counters"]["wkc_errors"] == 1


def test_a_fall_with_the_error_flag_stays_a_refused_transition() -> None:
    """A module pulled while SAFEOP -> OP is under way: the coupler falls to PREOP with the
    error flag and 0x8204 (seed 000 §7.7). That is the transition refused, logged as §7.7
    prints it ("failed!" then "aborted") at the check and retried every retry interval, not
    an abnormal state change (unchanged by the rule above; guards its error-flag condition)."""
    rig = build_rig(load_rig_spec(LINE_RIG), state_dir=None)
    link = _master(rig).links[0]
    events: list[Event] = []
    while link.pending is not AlState.OP:
        events += rig.step()
        assert rig.clock.now_us < 5 * US
    requested_us = link.requested_at_us
    events += rig.run_until(requested_us + 20 * MS)
    rig.devices["fastcat"].apply("unplug", {}, 2)
    events += rig.run_until(requested_us + 500 * MS)
    t = (requested_us + 20 * MS) / US
    check = (requested_us + _master(rig).check_delay_us) / US
    assert [text for _t, text in _texts(events, t)] == [
        "'Box 1 (FastCAT)' (1001): CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00').",
        "'Box 1 (FastCAT)' (1001): 'SAFEOP to OP' failed! Error: 'check device state for OP'. "
        "AL Status '0x0012' read and '0x0008' expected. AL Status Code '0x8204'",
        "'Box 1 (FastCAT)' (1001): state change aborted (requested 'OP', back to 'PREOP')."]
    assert [when for when, _text in _texts(events, t)][1:] == [check, check]
