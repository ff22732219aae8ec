"""Jog after the panel's Stop names the stop bit of the drive's own fieldbus and what clears it.

Before, every drive answered "halted (0x6040 bit 8) - clear the halt bit": a CiA 402 bit on a
Modbus drive, whose stop is Stp_cmd, R00 bit 2 (seed 004 ch. 1), and a bit the panel has no
control for. As RESET_HINT does for the reset (docs/servo-drive.md §Alarms).
"""

from __future__ import annotations

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo.drive import DriveConfig

HINTS = [
    ("modbus", "stopped (Stp_cmd, R00 bit 2) - Enable or Move clears it"),
    ("canopen", "halted (0x6040 bit 8) - Enable or Move clears it"),
    ("ethercat", "halted (0x6040 bit 8) - Enable or Move clears it"),
    ("profinet", "stopped (Stp_cmd, Control Word bit 2) - Enable or Move clears it"),
]


def _stopped(fieldbus: str) -> Sim:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    assert sim.drive.apply("enable", {"on": True}) is None
    sim.run(5)
    assert sim.drive.apply("jog", {"direction": 1}) is None
    sim.run(300)
    sim.drive.apply("stop", {})
    sim.run(1_000)
    assert round(sim.drive.velocity_user) == 0
    return sim


@pytest.mark.parametrize(("fieldbus", "answer"), HINTS)
def test_jog_after_stop_names_the_stop_bit_of_the_fieldbus(fieldbus: str, answer: str) -> None:
    """A review's run: Stop, then Jog."""
    sim = _stopped(fieldbus)
    assert sim.drive.apply("jog", {"direction": -1}) == answer
    sim.run(300)
    assert round(sim.drive.velocity_user) == 0  # the answer is right: nothing moves


@pytest.mark.parametrize("clear", ["enable", "move"])
def test_what_the_answer_says_clears_the_stop(clear: str) -> None:
    sim = _stopped("modbus")
    if clear == "enable":
        sim.drive.apply("enable", {"on": True})
    else:
        sim.drive.apply("move", {"position": 1000, "relative": False})
        sim.run(2_000)
    sim.run(1)
    assert sim.drive.apply("jog", {"direction": -1}) is None
    sim.run(300)
    assert sim.drive.velocity_user < 0


def test_a_canopen_masters_halt_is_named_as_0x6040_bit_8() -> None:
    sim = make_sim(DriveConfig(fieldbus="canopen"))
    sim.w(1, 3)
    sim.cw(*CANOPEN_ENABLE)
    sim.cw(0x010F)  # halt
    assert sim.drive.motion_blocked() == "halted (0x6040 bit 8) - Enable or Move clears it"


def test_a_profinet_masters_stop_is_stp_cmd_of_its_control_word() -> None:
    """Seed 004 ch. 6: the Profinet Control Word is R00 (the worked example writes 0x0003,
    0x0043, 0x0023 to "Registro 0 control_word"), so its stop is Stp_cmd, bit 2 (ch. 1)."""
    sim = make_sim(DriveConfig(fieldbus="profinet"))
    sim.w(1, 3)
    sim.w(13, 6000)
    sim.w(0, 0x03)
    sim.run(300)
    sim.w(0, 0x07)  # Stp_cmd
    sim.run(1_000)
    assert round(sim.drive.velocity_user) == 0
    assert sim.drive.motion_blocked() == \
        "stopped (Stp_cmd, Control Word bit 2) - Enable or Move clears it"
