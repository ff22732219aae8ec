"""The Drive tab shows the target of the mode in force, never another mode's.

R09 target_position is the positioner's set-point (seed 004 ch. 1 quick reference; ch. 2
"Select": R09 or R30 in "modo posizionatore"), R13 target_velocity the speed control's (ch. 2
"Select" in "modo controllo di velocità"). The Position row read "target 0" while the axis
jogged at 1000 u/s in mode 3, and "target 6000" (the last move's) while homing searched the
marker: a trainee read a move to 0 or 6000 that the drive was not making.
"""

from __future__ import annotations

from pathlib import Path

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.drive.drive_state import state_rows


def _rows(tmp_path: Path, steps: list[tuple[str, dict]]) -> dict[str, str]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path)
    rig.run_until(500_000)
    t = 500_000
    for action, args in steps:
        rig.apply("drive", action, args)
        t += 500_000
        rig.run_until(t)
    return dict(state_rows(rig.snapshot()["devices"]["drive"]))


def test_the_positioner_shows_its_target_position(tmp_path: Path) -> None:
    rows = _rows(tmp_path, [("enable", {"on": True}), ("move", {"position": 6000})])
    assert "target 6000" in rows["Position"]
    assert "target" not in rows["Velocity"]


def test_velocity_mode_shows_the_target_velocity_not_r09(tmp_path: Path) -> None:
    rows = _rows(tmp_path, [("enable", {"on": True}), ("move", {"position": 6000}),
                            ("jog", {"direction": 1})])
    assert "target" not in rows["Position"]
    assert "target 1000 u/s" in rows["Velocity"]


def test_homing_shows_no_stale_position_target(tmp_path: Path) -> None:
    rows = _rows(tmp_path, [("enable", {"on": True}), ("move", {"position": 6000}),
                            ("home", {})])
    assert rows["Mode"] == "6 homing"
    assert "target" not in rows["Position"] and "target" not in rows["Velocity"]


def test_velocity_mode_with_select_high_shows_aux_in_1(tmp_path: Path) -> None:
    """Ch. 2 "Select" in speed control: with the input high the speed is R30 aux_in_1."""
    rows = _rows(tmp_path, [("enable", {"on": True}),
                            ("write_register", {"register": 30, "value": 250}),
                            ("set_input", {"name": "select", "value": True}),
                            ("jog", {"direction": 1})])
    assert "target 250 u/s" in rows["Velocity"]
