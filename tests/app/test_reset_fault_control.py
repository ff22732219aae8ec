"""The FastCAT's Reset fault box says what it is: the level of bit 0x5200:1, whose rising edge
resets (seed 000 §6.17 "Scrivendo quest'oggetto è possibile comandare un reset dell'allarme";
§7 "Il reset degli emergency resettabili avviene alzando il bit di Reset Fault").

The UI audit: after a reset the box stays ticked (it mirrors the bit, which the coupler keeps
at 1 until written 0), and trainees read it as a stuck reset. The bit is not faked: the box
still shows 0x5200:1; its hint says what the box is, and while the bit is 1 a note under it
says the reset acted on the 0 -> 1 edge and how to make the next one.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
from served_dashboard import drawn, served_default_rig

from app.screenshots import ServedRig


@pytest.fixture
def served() -> Iterator[ServedRig]:
    with served_default_rig(8.0) as live:  # the first internal-bus scan builds 0x5200 (§5)
        yield live


def box_shows(box: Any, value: bool) -> None:
    """The box is a Synced widget: the model's value reaches it on viser's event loop,
    shortly after the frame was drawn."""
    deadline = time.monotonic() + 10.0
    while box.value is not value and time.monotonic() < deadline:
        time.sleep(0.01)
    assert box.value is value


def test_reset_fault_box_says_it_is_the_bit_and_acts_on_the_rising_edge(
        served: ServedRig) -> None:
    control = served.dashboard._panels.control  # type: ignore[union-attr]
    hint = str(control.reset_box.hint)
    assert "0x5200:1" in hint and "rising edge" in hint and "0 → 1" in hint, hint
    assert "untick" in hint.lower(), hint
    drawn(served)
    assert not control.reset_note.visible  # bit 0: nothing to explain
    served.command("fastcat", "set_reset_fault", {"on": True})
    drawn(served)
    box_shows(control.reset_box, True)  # the bit's value, not faked back to 0
    assert control.reset_note.visible
    note = str(control.reset_note.content)
    assert "0x5200:1 = 1" in note and "0 → 1" in note and "untick" in note.lower(), note
    served.command("fastcat", "set_reset_fault", {"on": False})
    drawn(served)
    box_shows(control.reset_box, False)
    assert not control.reset_note.visible
