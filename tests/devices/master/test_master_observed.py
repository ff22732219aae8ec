"""What the master says about a line fault is what a real master observes (seed 003 events;
ETG.1000): its own port's link, the slaves that stop answering (the working counter of its
AL status read), the link bits its slaves' ESCs report (DL status 0x0110), the states and
AL status codes it reads back. Which cable was pulled or which slave was switched off is the
simulator's knowledge: the snapshot's ``injected``, for the instructor's view only."""

from __future__ import annotations

import re
from typing import Any

import pytest
from line_bench import IN_OP_US, US, line_in_op, master_view

from app.rig import Rig

# Words only the simulator knows: a real master sees no cable and no supply.
CAUSE_WORDS = re.compile(r"cable|pulled|power|\boff\b|unplug", re.IGNORECASE)

FAULTS: list[tuple[str, str, dict[str, Any]]] = [
    *[("master", "pull_cable", {"cable": c}) for c in range(4)],
    *[("master", "power_slave", {"position": p, "on": False}) for p in range(4)],
    ("trscat", "link", {"connected": False, "port": "in"}),
    ("trscat", "link", {"connected": False, "port": "out"}),
    ("cpx", "cable", {"connected": False, "port": "in"}),
    ("cpx", "cable", {"connected": False, "port": "out"}),
]


def _faulted(device: str, action: str, args: dict[str, Any]) -> Rig:
    rig = line_in_op()
    rig.apply(device, action, args)
    rig.run_until(IN_OP_US + US // 2)
    return rig


def _master_texts(rig: Rig) -> list[str]:
    view = master_view(rig)
    return [line["text"] for line in view["log"]] + [s["diagnosis"] for s in view["slaves"]]


@pytest.mark.parametrize(
    ("device", "action", "args"),
    FAULTS,
    ids=lambda v: v if isinstance(v, str) else "-".join(map(str, v.values())),
)
def test_no_master_line_or_diagnosis_names_the_cause(device, action, args) -> None:
    rig = _faulted(device, action, args)
    view = master_view(rig)
    assert not all(s["present"] for s in view["slaves"])  # the fault cost the master slaves
    named = [text for text in _master_texts(rig) if CAUSE_WORDS.search(text)]
    assert named == []
    # The seed 003 diagnostic structure holds what the master reads, not the line's truth.
    for slave in view["slaves"]:
        assert "powered" not in slave and "link" not in slave


def test_cable_2_lost_slaves_as_the_master_sees_them() -> None:
    """Slaves 2..3 stop answering: the AL status read's working counter drops to 2 of 4 and
    the TRS-CAT (position 1) reports no link on its port 1 (OUT)."""
    rig = _faulted("master", "pull_cable", {"cable": 2})
    view = master_view(rig)
    texts = [line["text"] for line in view["log"]]
    assert texts[-3:] == [
        "'Box 3 (CPX-E-EC)' (1003): slave lost: no answer from position 2 on.",
        "'Drive 4 (SelemaDriveECAT)' (1004): slave lost: no answer from position 2 on.",
        "'Device 1 (EtherCAT)': slave(s) at position(s) 2, 3 lost: no answer from position 2 "
        "on (working counter 2, 4 expected); no link on port 1 (OUT) of position 1.",
    ]
    assert [s["diagnosis"] for s in view["slaves"]] == [
        "",
        "",
        *["no answer from position 2 on (no link on port 1 (OUT) of position 1)"] * 2,
    ]


def test_cable_0_is_link_down_on_the_master_port() -> None:
    rig = _faulted("master", "pull_cable", {"cable": 0})
    own = [
        line["text"]
        for line in master_view(rig)["log"]
        if line["text"].startswith("'Device 1 (EtherCAT)': slave(s)")
    ]
    assert own == [
        (
            "'Device 1 (EtherCAT)': slave(s) at position(s) 0, 1, 2, 3 lost: no answer "
            "from position 0 on (working counter 0, 4 expected); link down on the "
            "master port."
        )
    ]


def test_a_slave_switched_off_reads_as_its_cable_pulled() -> None:
    """A master cannot tell a slave without supply from the cable to it pulled: the same
    lines, the same diagnoses; only the injected cause differs (instructor's view). The
    CPX-E-EC's own undervoltage emergency (0x3120, sent in its hold-up time) is something
    the master reads: left out of the comparison."""
    off, pulled = (
        _faulted("master", "power_slave", {"position": 2, "on": False}),
        _faulted("master", "pull_cable", {"cable": 2}),
    )
    assert [t for t in _master_texts(off) if "Emergency" not in t] == _master_texts(pulled)
    assert master_view(off)["injected"]["lost"] == [
        {"position": 2, "cause": "powered off"},
        {"position": 3, "cause": "the slave at position 2 is off"},
    ]
    assert master_view(pulled)["injected"]["lost"] == [
        {"position": 2, "cause": "cable 2 pulled"},
        {"position": 3, "cause": "cable 2 pulled"},
    ]


def test_the_injected_view_holds_the_line_s_truth_and_clears_on_recovery() -> None:
    rig = _faulted("master", "power_slave", {"position": 3, "on": False})
    view = master_view(rig)
    assert view["injected"]["powered"] == [True, True, True, False]
    assert view["injected"]["link"] == [True, True, True, True]
    rig.apply("master", "power_slave", {"position": 3, "on": True})
    rig.apply("master", "dc_fault", {"kind": "drift"})
    rig.run_until(IN_OP_US + 6 * US)
    view = master_view(rig)
    assert view["injected"]["lost"] == [] and view["injected"]["dc_fault"] == "drift"
    assert "fault" not in view["dc"]  # the DC unit shows its state and deviation, no cause


def test_a_lost_slave_s_cause_follows_the_line_while_it_stays_lost() -> None:
    """The instructor's Causes row is the line's truth now, not the one of the step the slave
    was lost in: slave 2 off, then cable 1 pulled and slave 2 back on, slaves 1..3 are lost
    because of the cable alone (before, 2 and 3 kept "powered off" / "the slave at position 2
    is off" while both were on)."""
    rig = _faulted("master", "power_slave", {"position": 2, "on": False})
    rig.apply("master", "pull_cable", {"cable": 1})
    rig.apply("master", "power_slave", {"position": 2, "on": True})
    rig.run_until(IN_OP_US + US)
    assert master_view(rig)["injected"]["lost"] == [
        {"position": p, "cause": "cable 1 pulled"} for p in (1, 2, 3)
    ]


def test_a_cause_just_removed_is_kept_until_the_slave_answers() -> None:
    """Powered again, the slave is found at the next step: until then (the frame published
    right after the command) its cause stays the one it was lost for, not a made-up one."""
    rig = _faulted("master", "power_slave", {"position": 3, "on": False})
    rig.apply("master", "power_slave", {"position": 3, "on": True})
    assert master_view(rig)["injected"]["lost"] == [{"position": 3, "cause": "powered off"}]


def test_each_lost_slave_names_the_current_first_silent_position() -> None:
    """Cable 3 out, then cable 2: the gap grows towards the master and the CPX-E-EC's and the
    drive's diagnoses both say where nothing answers now; cable 2 back, the drive's says
    position 3 again."""
    rig = _faulted("master", "pull_cable", {"cable": 3})
    behind_2 = "no answer from position 3 on (no link on port 1 (OUT) of position 2)"
    assert [s["diagnosis"] for s in master_view(rig)["slaves"]] == ["", "", "", behind_2]
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.run_until(IN_OP_US + US)
    behind_1 = "no answer from position 2 on (no link on port 1 (OUT) of position 1)"
    assert [s["diagnosis"] for s in master_view(rig)["slaves"]] == ["", "", behind_1, behind_1]
    rig.apply("master", "plug_cable", {"cable": 2})
    rig.run_until(IN_OP_US + 2 * US)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [True, True, True, False]
    assert [s["diagnosis"] for s in view["slaves"]] == ["", "", "", behind_2]
