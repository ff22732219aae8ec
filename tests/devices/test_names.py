"""``did_you_mean``: the one hint every "unknown X" message of a rig file, a scenario, an
exercise file and a device command ends with (devices/names.py)."""

from __future__ import annotations

import pytest

from devices.names import close_names, closest_slip, did_you_mean


@pytest.mark.parametrize(("name", "known", "hint"), [
    ("slav", ("event", "slave", "to", "once"), "; did you mean 'slave'?"),
    ("acton", ("target", "action"), "; did you mean 'action'?"),
    ("db16", ("DB16", "DI16", "DO16"), "; did you mean 'DB16'?"),  # a case slip
    ("resynch", ("slave_state", "resync"), "; did you mean 'resync'?"),
    ("wheels", ("id", "node_id", "fieldbus"), ""),  # nothing close: no guess
    ("x", (), ""),
])
def test_the_hint_names_the_closest_allowed_name_or_nothing(name: str, known: tuple[str, ...],
                                                            hint: str) -> None:
    assert did_you_mean(name, known) == hint


def test_close_names_keeps_the_callers_spelling_and_best_first() -> None:
    assert close_names("Slave", ["slave_state", "slave"], n=2) == ["slave", "slave_state"]
    assert close_names("drive", ["drive"]) == []  # the name itself is not a slip


def test_closest_slip_names_the_key_most_like_an_allowed_one() -> None:
    keys = ("at", "after", "target", "action")
    assert closest_slip(["active", "actoin"], keys) == "actoin"  # active: an argument
    assert closest_slip(["on", "targt"], keys) == "targt"
    assert closest_slip(["on", "speed"], keys) is None  # no slip: nothing to name
    assert closest_slip(["aftr", "Traget"], ("target",)) == "Traget"
