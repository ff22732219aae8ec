"""The phase "running" means every slave the master reads is at its target; a trainee reads it
as "all is well". Slaves lost behind a pulled cable and DC slaves held in SAFEOP are said next
to it (docs/ethercat-master.md "Start-up", seed 003 names no phases)."""

from __future__ import annotations

from line_bench import IN_OP_US, LINE_RIG, US, line_in_op, master_view

from app.rig_config import build_rig, load_rig_spec


def test_a_healthy_line_in_op_has_no_note() -> None:
    view = master_view(line_in_op())
    assert (view["phase"], view["phase_note"], view["phase_note_short"]) == ("running", "", "")


def test_slaves_lost_behind_a_pulled_cable_are_said_next_to_running() -> None:
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": 2})  # the CPX-E-EC and the drive behind it
    rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert view["phase"] == "running"  # the snapshot's key is unchanged (recordings)
    assert (view["phase_note"], view["phase_note_short"]) == ("2 slaves lost", "2 lost")
    rig.apply("master", "plug_cable", {"cable": 2})
    rig.run_until(IN_OP_US + 3 * US)
    view = master_view(rig)
    assert (view["phase"], view["phase_note"]) == ("running", "")


def test_dc_slaves_held_in_safeop_are_said_next_to_running() -> None:
    """Seed 003 NOT_SYNCHRONIZED: "all the slaves involved go to the SAFE_OP state"; the master
    reads them at the target it gives them, but not at its own target OP."""
    rig = line_in_op()
    rig.apply("master", "dc_fault", {"kind": "drift"})
    rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert view["dc"]["state"] == "NOT_SYNCHRONIZED" and view["phase"] == "running"
    assert view["phase_note"] == "2 DC slaves held in SAFEOP"
    assert view["phase_note_short"] == "2 held"


def test_lost_and_held_together() -> None:
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": 3})  # the drive
    rig.apply("master", "dc_fault", {"kind": "drift"})
    rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert view["phase_note"] == "1 slave lost, 2 DC slaves held in SAFEOP"
    assert view["phase_note_short"] == "1 lost, 2 held"


def test_a_slave_never_found_is_said_apart_from_the_lost_ones() -> None:
    """A slave the description expects and that never answered since start-up is "not found"
    (docs/ethercat-master.md "What the master knows"); on the small screen it counts as lost."""
    rig = build_rig(load_rig_spec(LINE_RIG))
    rig.apply("master", "power_slave", {"position": 3, "on": False})  # the drive
    rig.run_until(IN_OP_US)
    view = master_view(rig)
    assert view["phase"] == "running"
    assert (view["phase_note"], view["phase_note_short"]) == ("1 slave not found", "1 lost")


def test_nothing_answering_leaves_the_note_to_the_phase() -> None:
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": 0})
    rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert (view["phase"], view["phase_note"]) == ("waiting_link", "")
