"""The End of Job output (CN2 pin 12, R05 bit 6, 0x6041 bit 10 in pp) against seed 004 ch. 2
"I/O digitali": "Quando il posizionamento è terminato e l'errore di inseguimento è inferiore a
quello specificato nella relativa finestra (following_error_window), l'uscita End of Job viene
alzata"."""

from __future__ import annotations

import pytest
from servo_helpers import Sim, make_sim

from devices.servo import ds402
from devices.servo.registers import DISABLED_32

EOJ = 0x40  # R05 bit 6 in the positioners


def _jammed_move(mode: int, window: int) -> Sim:
    """The load jammed at 0 (feed 6000): the profile to 3000 ends with the following error
    exactly 3000 (0.5 turn, exact in binary). R04 at its top keeps alarm 16 away."""
    sim = make_sim()
    sim.w(3, window)
    sim.w(4, 0x1FFF)
    sim.w(12, 20000)
    sim.w(10, 200)
    sim.w(11, 200)
    sim.drive.apply("jam_load", {"active": True})
    if mode == 1:
        sim.w(9, 3000)
        sim.w(0, 0x03)
        sim.w(0, 0x23)
    else:  # 500 pulses of R02 * R25 / (R26 * R24) = 6 units each
        sim.w(24, 1000)
        sim.w(1, -1)
        sim.w(0, 0x03)
        sim.drive.apply("pulses", {"count": 500})
    sim.run(1000)
    assert sim.drive.trajectory.at_target and sim.drive.following_error_user == 3000.0
    return sim


@pytest.mark.parametrize("mode", [1, -1])
@pytest.mark.parametrize(("window", "raised"), [(2999, False), (3000, False), (3001, True),
                                                (DISABLED_32, True)])
def test_end_of_job_wants_the_following_error_below_the_window(mode: int, window: int,
                                                               raised: bool) -> None:
    """"Inferiore": strictly below R03, so an error equal to the window keeps End of Job low
    (and alarm 16 away: "superato"). R03 = 0xFFFFFFFF disables the check (ch. 4, 0x6065): the
    end of the profile alone raises it. Mode -1 is "del tutto simile"."""
    sim = _jammed_move(mode, window)
    assert sim.drive.outputs()["end_of_job"] is raised
    assert bool(sim.r05 & EOJ) is raised
    assert sim.drive.read_register(46) == 0
    if mode == 1:  # 0x6041 bit 10 "target reached" in pp is End of Job
        assert bool(sim.drive.statusword & ds402.SW_TARGET_REACHED) is raised


def test_end_of_job_never_comes_with_a_zero_window() -> None:
    """R03 = 0: no following error is below 0, not even none at all, so End of Job stays low
    on an axis standing exactly at its target (R04 at its top keeps alarm 16 away)."""
    sim = make_sim()
    sim.w(3, 0)
    sim.w(4, 0x1FFF)
    sim.w(9, 300)
    sim.w(0, 0x03)
    sim.w(0, 0x23)
    sim.run(2000)
    assert sim.drive.position_user == 300 and sim.drive.following_error_user == 0.0
    assert not sim.drive.outputs()["end_of_job"] and not sim.r05 & EOJ
    sim.w(3, 1)  # one unit of window: the standing axis is within it
    sim.run(1)
    assert sim.drive.outputs()["end_of_job"] and sim.r05 & EOJ
