"""The Line tab shows a trainee what the master observes (docs/ethercat-master.md "What the
master knows"): which slaves answer, their states and AL status codes, DC state and
deviation. Which cable was pulled, which slave is off and which DC fault was injected are the
instructor's rows only (docs/classroom.md: causes are built per instructor connection)."""

from __future__ import annotations

import re
from typing import Any

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.line.bodies import header_text
from app.ui.line.controls import slave_options
from app.ui.line.master_panel import live_table, slaves_table, status_table
from app.ui.line.scene import slave_entries
from app.ui.panels.per_client import split_instructor

CAUSE_WORDS = re.compile(r"cable|pulled|power|\boff\b|drift", re.IGNORECASE)
ORDER = ["fastcat", "trscat", "cpx", "drive_ec-ecat"]


def _faulted_master() -> dict[str, Any]:
    """The default line in OP, then cable 2 pulled and the DC fault ``drift`` injected."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.advance(8000)
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.apply("master", "power_slave", {"position": 1, "on": False})
    rig.apply("master", "dc_fault", {"kind": "drift"})
    rig.advance(200)
    return rig.snapshot()["devices"]["master"]


def test_the_shared_master_panel_names_no_injected_cause() -> None:
    master = _faulted_master()
    public, instructor = split_instructor(status_table(master), "fr-line-master-causes")
    shared = [public, slaves_table(master["slaves"], "OP"), live_table(master)]
    shared += [
        header_text(entry, i) for i, entry in enumerate(slave_entries(master, ORDER).values())
    ]
    assert [CAUSE_WORDS.findall(text) for text in shared] == [[]] * len(shared)
    # What the master sees: the slaves from position 1 on do not answer.
    assert "not seen" in shared[1] and ">no<" in shared[1]
    # The instructor's rows: the cable, the slave off, the DC fault, each lost slave's cause.
    assert "2 trscat -&gt; cpx pulled" in instructor
    assert "1 trscat off" in instructor and "DC fault drift" in instructor
    assert "1: powered off" in instructor and "3: the slave at position 1 is off" in instructor


def test_the_instructor_s_slave_list_marks_the_slaves_off() -> None:
    """The Cables and power folder (instructor only) still says which slave is off."""
    master = _faulted_master()
    assert slave_options(master, ORDER)[1] == "1 trscat (off)"


def test_the_phase_without_an_answering_slave_is_named_as_the_master_reads_it() -> None:
    """Seed 003: with link the master "starts sending packets"; the phase in which not one
    slave answers them read "no answer" in the panel, which a trainee can take for the
    master's own silence."""
    text = status_table({"phase": "no_answer", "link": True, "target": "OP"})
    assert ">no slave answers<" in text and ">no answer<" not in text


def test_dc_idle_shows_no_deviation() -> None:
    """Seed 003 IDLE: the master clock is independent of the slaves; the master measures no
    deviation (``deviation_ns`` None) and the panel says so, not "0 ns" (in sync)."""
    text = live_table({"dc": {"state": "IDLE", "deviation_ns": None, "window_ns": 1000}})
    assert "deviation not measured / window 1000\u00a0ns" in text
    assert "None" not in text and "0\u00a0ns /" not in text
    text = live_table({"dc": {"state": "COMPENSATING", "deviation_ns": -12, "window_ns": 1000}})
    assert "deviation -12\u00a0ns / window 1000\u00a0ns" in text


def test_running_with_slaves_lost_or_held_is_no_green_running() -> None:
    """"running" is every slave the master reads at its target; a trainee reads a green
    "running" as all is well. Slaves lost or DC slaves held in SAFEOP are said with it, in
    the warning colour (docs/ethercat-master.md "Start-up")."""
    healthy = status_table({"phase": "running", "phase_note": "", "link": True,
                            "target": "OP"})
    assert '<span class="fr-badge fr-ok">running</span>' in healthy
    noted = status_table({"phase": "running", "link": True, "target": "OP",
                          "phase_note": "2 slaves lost, 2 DC slaves held in SAFEOP"})
    assert ('<span class="fr-badge fr-warn">running</span> <span class="fr-line-warn">2 slaves '
            'lost, 2 DC slaves held in SAFEOP</span>') in noted


def test_the_phase_badge_holds_the_phase_and_the_note_follows_it() -> None:
    """The badge held the whole sentence, "running, 2 DC slaves held in SAFEOP", and broke
    over two lines at the 400 px panel: the badge is the phase's word (one line, whatever the
    note), the note its own text after it (tests/browser/test_table_wrapping.py looks)."""
    held = status_table({"phase": "running", "link": True, "target": "OP",
                         "phase_note": "2 DC slaves held in SAFEOP", "external": True})
    badge = re.search(r'<span class="fr-badge fr-warn">([^<]*)</span>', held)
    assert badge is not None and badge.group(1) == "running"
    assert '</span> <span class="fr-line-warn">2 DC slaves held in SAFEOP</span>' \
           " (external master)" in held
    starting = status_table({"phase": "init_commands", "phase_note": ""})
    assert '<span class="fr-badge fr-warn">init commands</span></td>' in starting
