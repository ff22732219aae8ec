"""Alarms (seed 004 ch. 3; 0x603F table ch. 5; Profinet alarms ch. 6): code in R46 and 0x603F,
the documented effect, reset only once the cause is gone, the display."""

from __future__ import annotations

import pytest
from servo_helpers import Sim, make_sim

from devices.servo.alarms import DRIVE_ALARMS, Effect, alarm_table
from devices.servo.drive import DriveConfig
from devices.servo.ds402 import State

ALL_CODES = sorted(alarm_table("ethercat"))


def _running(sim: Sim) -> None:
    sim.w(1, 3)
    sim.w(13, 30000)
    sim.w(0, 0x03)
    sim.run(300)


def test_the_table_has_every_code_of_the_seed() -> None:
    """Ch. 3 codes 1-10, 13-16, 22-26; ch. 5 adds 11, 12, 20, 21 and 30-35."""
    assert [*range(1, 17), 20, 21, *range(22, 27), *range(30, 36)] == ALL_CODES
    assert sorted(alarm_table("profinet")) == [*range(1, 17), 20, 21, *range(22, 27),
                                               *range(30, 35)]


RELEASED = {1, 3, 4, 8, 9, 14, 16, 22, 23, 24, 25, 26}  # "Asse rilasciato immediatamente"
ERROR_CODES = {1: 0x2340, 2: 0x7120, 3: 0x2310, 4: 0x3210, 5: 0x3220, 6: 0x4310, 7: 0x5220,
               8: 0x7300, 9: 0x5500, 10: 0x7110, 11: 0x7500, 12: 0x7320, 13: 0x7500,
               14: 0x7320, 15: 0x5500, 16: 0x8611, 20: 0x8612, 21: 0x8612, 22: 0x1000,
               23: 0x7300, 24: 0x7300, 25: 0x7300, 26: 0x5114, 30: 0x1000, 31: 0x7500,
               32: 0x7500, 33: 0x6320, 34: 0x8700, 35: 0x5530}


@pytest.mark.parametrize("code", ALL_CODES)
def test_inject_reset_and_clear(code: int) -> None:
    sim = make_sim(DriveConfig(fieldbus="ethercat"))
    _running(sim)
    sim.drive.apply("inject_alarm", {"code": code})
    injected_at = sim.t_us / 1e6
    spec = sim.drive.alarm_table[code]
    assert (spec.effect is Effect.RELEASE) == (code in RELEASED)
    if code in RELEASED:
        assert sim.drive.state is State.FAULT  # torque off at once
    else:
        assert sim.drive.state is State.FAULT_REACTION_ACTIVE  # emergency ramp first
        sim.run_until(lambda: sim.drive.state is State.FAULT, 2_000)
    assert sim.drive.read_register(46) == code
    assert sim.drive.od.read(0x603F, 0) == ERROR_CODES[code]
    assert sim.drive.read_register(5) & 0x08  # Alm_st
    assert sim.drive.display == f"{code:2d}"
    sim.events += sim.drive.drain_events()
    assert sim.kinds("alarm")[-1] == {"t": injected_at, "device": "servo", "event": "alarm",
                                      "code": str(code), "name": spec.name, "active": True}
    sim.w(0, 0x08)  # reset refused: the injected cause is still there
    assert sim.drive.read_register(46) == code
    sim.drive.apply("clear_alarm", {"code": code})
    sim.w(0, 0x00)
    sim.w(0, 0x08)
    if not spec.resettable:  # 35 on EtherCAT: only a power cycle (docs/ethercat-coe.md)
        assert sim.drive.read_register(46) == code
        sim.drive.apply("power", {"on": False})
        sim.drive.apply("power", {"on": True})
        sim.run(60)
    assert sim.drive.read_register(46) == 0
    assert sim.drive.od.read(0x603F, 0) == 0
    assert sim.drive.state is State.SWITCH_ON_DISABLED
    if spec.resettable:  # a power cycle drops the alarms without an alarm event
        assert sim.kinds("alarm")[-1]["active"] is False


def test_ethercat_reset_by_0x80_on_0x6040() -> None:
    """Ch. 5 "Reset allarmi": write 0x80 to 0x6040."""
    sim = make_sim(DriveConfig(fieldbus="ethercat"))
    sim.drive.apply("inject_alarm", {"code": "SYNC_TIMEOUT"})
    sim.drive.apply("clear_alarm", {"code": 34})
    sim.drive.od.write(0x6040, 0, 0x80)
    assert sim.drive.read_register(46) == 0


@pytest.mark.parametrize(("code", "resettable"), [(30, False), (31, False), (32, False),
                                                  (33, False), (34, True)])
def test_profinet_alarms_30_to_33_are_not_resettable(code: int, resettable: bool) -> None:
    """Ch. 6: reset with 0x08 on the control word; 30-33 "Resettabile NO"."""
    sim = make_sim(DriveConfig(fieldbus="profinet"))
    sim.drive.apply("inject_alarm", {"code": code})
    sim.drive.apply("clear_alarm", {"code": code})
    sim.w(0, 0x08)
    assert (sim.drive.read_register(46) == 0) == resettable
    sim.drive.apply("power", {"on": False})
    sim.drive.apply("power", {"on": True})
    assert sim.drive.read_register(46) == 0  # a power cycle clears everything


def test_load_jam_raises_following_error_alarm_16() -> None:
    """Following error > R03 for longer than R04 ms: alarm 16, axis released."""
    sim = make_sim()
    sim.w(3, 500)
    sim.w(4, 50)
    _running(sim)
    sim.drive.apply("jam_load", {"active": True})
    took = sim.run_until(lambda: sim.drive.read_register(46) == 16, 1_000)
    # 30000 u/s against a blocked load: 500 units of error after ~17 ms, then 50 ms more
    assert 60 <= took <= 75
    assert sim.drive.state is State.FAULT
    assert sim.drive.display == "16"


def test_following_error_window_0xffffffff_disables_the_check() -> None:
    sim = make_sim()
    sim.w(3, 0xFFFF_FFFF)
    _running(sim)
    sim.drive.apply("jam_load", {"active": True})
    sim.run(1000)
    assert sim.drive.read_register(46) == 0
    assert sim.drive.read_register(5) & 0x80  # the blocked axis stands: zero speed


def test_following_error_flag_in_positioner() -> None:
    """R05 bit 7 and 0x6041 bit 13 in the positioner while the error exceeds the window."""
    sim = make_sim()
    sim.w(3, 100)
    sim.w(4, 1000)
    sim.w(0, 0x03)
    sim.w(9, 60000)
    sim.drive.apply("jam_load", {"active": True})
    sim.w(0, 0x23)
    sim.run(200)
    assert sim.drive.read_register(5) & 0x80
    assert sim.drive.statusword & 0x2000


@pytest.mark.parametrize(("velocity", "code"), [(-30000, 20), (30000, 21)])
def test_limit_switches_raise_ls1_ls2(velocity: int, code: int) -> None:
    """Alarms 20 / 21 (LS1 / LS2, 0x603F 0x8612) when the axis runs into a limit switch the
    homing method uses (17 / 18: the switch's edge; tests/devices/servo/
    test_servo_limit_inputs.py for the methods that leave the pins digital inputs)."""
    sim = make_sim(DriveConfig(neg_limit=-12000, pos_limit=12000))
    sim.w(18, 17 if code == 20 else 18)
    sim.w(1, 3)
    sim.w(13, velocity)
    sim.w(0, 0x03)
    sim.run_until(lambda: sim.drive.read_register(46) != 0, 3_000)
    assert sim.drive.read_register(46) == code
    assert sim.drive.statusword & 0x0800  # internal limit active
    sim.run_until(lambda: sim.drive.state is State.FAULT, 1_000)
    sim.w(13, -velocity)
    sim.w(0, 0x08)
    sim.w(0, 0x03)  # reset, then drive away from the switch
    sim.run(500)
    assert sim.drive.read_register(46) == 0
    assert not sim.drive.snapshot()["limits"]["neg" if code == 20 else "pos"]


def test_unknown_alarm_codes_are_refused() -> None:
    sim = make_sim()
    from devices.device import CommandError
    for code in (0, 17, 18, 19, 27, 36, "NO_SUCH"):
        with pytest.raises(CommandError):
            sim.drive.apply("inject_alarm", {"code": code})
    assert sim.drive.read_register(46) == 0


def test_first_alarm_stays_in_r46() -> None:
    sim = make_sim()
    sim.drive.apply("inject_alarm", {"code": 4})
    sim.drive.apply("inject_alarm", {"code": 2})
    assert sim.drive.read_register(46) == 4
    sim.drive.apply("clear_alarm", {"code": 4})
    sim.w(0, 0x08)
    assert sim.drive.read_register(46) == 2  # 2 still has its cause


def test_every_drive_alarm_has_a_description() -> None:
    for spec in DRIVE_ALARMS.values():
        assert spec.description and spec.name.isupper()
