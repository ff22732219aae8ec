"""A DC slave held in SAFEOP (seed 003 NOT_SYNCHRONIZED: "all the slaves involved go to the
SAFE_OP state") that leaves its state on its own is brought back to SAFEOP only: the TwinCAT
lines (seed 000 §7.7, "Try to go back to 'OP'", "state change aborted (requested 'OP', ...)")
name the state the master takes it to, not the master's target it is held below
(docs/ethercat-master.md "Start-up" 5)."""

from __future__ import annotations

from line_bench import IN_OP_US, US, line_in_op

from app.rig import Rig

TRS = "'Box 2 (TRS-CAT)' (1002): "
CPX = "'Box 3 (CPX-E-EC)' (1003): "


def _held() -> tuple[Rig, int]:
    """The line in OP, then a drifting reference clock: the TRS-CAT and the CPX-E-EC held in
    SAFEOP; the master's log length then."""
    rig = line_in_op()
    rig.apply("master", "dc_fault", {"kind": "drift"})
    rig.run_until(IN_OP_US + US // 2)
    assert [s["state"] for s in rig.snapshot()["devices"]["master"]["slaves"]] == [
        "OP", "SAFEOP", "SAFEOP", "OP"]
    return rig, len(rig.devices["master"].log)


def _texts(rig: Rig, mark: int) -> list[str]:
    return [row["text"] for row in list(rig.devices["master"].log)[mark:]]


def test_a_held_dc_slave_that_restarts_is_taken_back_to_safeop_and_the_line_says_so() -> None:
    rig, mark = _held()
    rig.apply("cpx", "restart", {})
    rig.run_until(IN_OP_US + 2 * US)
    assert _texts(rig, mark) == [
        CPX + "abnormal state change (from 'SAFEOP' to 'INIT') with code 0x0000. Try to go "
              "back to 'SAFEOP'..."]
    assert rig.snapshot()["devices"]["master"]["slaves"][2]["state"] == "SAFEOP"


def test_a_held_dc_slave_refused_on_its_way_back_names_safeop_as_requested() -> None:
    rig, mark = _held()
    rig.apply("trscat", "inject_sm_fault", {"fault": "sm_invalid_size", "sm": 2})
    rig.apply("trscat", "power", {"on": False})
    rig.apply("trscat", "power", {"on": True})
    rig.run_until(IN_OP_US + 3 * US)
    texts = _texts(rig, mark)
    assert texts[0] == (TRS + "abnormal state change (from 'SAFEOP' to 'INIT') with code "
                              "0x0000. Try to go back to 'SAFEOP'...")
    aborted = [t for t in texts if "state change aborted" in t]
    assert aborted and set(aborted) == {
        TRS + "state change aborted (requested 'SAFEOP', back to 'PREOP')."}


def test_a_request_made_for_op_keeps_op_when_dc_holds_before_its_check() -> None:
    """dc_sync_lost: the CPX-E-EC's sync error (0x001A) drops it to SAFEOP while DC is still
    COMPENSATING; the master asks OP, and DC falls to NOT_SYNCHRONIZED before the check 141 ms
    later. OP was what it requested: the aborted line keeps it."""
    rig = line_in_op()
    rig.apply("master", "dc_fault", {"kind": "sync0_lost"})
    mark = len(rig.devices["master"].log)
    rig.run_until(IN_OP_US + US)
    aborted = [t for t in _texts(rig, mark) if "state change aborted" in t]
    assert aborted and all("(requested 'OP', back to 'SAFEOP')" in t for t in aborted)
