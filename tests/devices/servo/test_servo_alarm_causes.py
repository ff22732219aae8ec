"""An injected alarm's cause lasts until clear_alarm, also across a power cycle (seed 004 ch. 5
"Reset allarmi": "la condizione di allarme persiste"; docs/servo-drive.md §Alarms): the drive
finds it again at power-up. Event alarms (following error, limit switch) do not come back."""

from __future__ import annotations

from servo_helpers import Sim, make_sim

from devices.servo.alarms import AlarmBank, alarm_table
from devices.servo.ds402 import State

POSITION_SENSOR = 8


def _power_cycle(sim: Sim) -> None:
    sim.drive.apply("power", {"on": False})
    sim.run(10)
    sim.drive.apply("power", {"on": True})
    sim.run(100)  # past the self test


def test_an_injected_cause_outlasts_a_power_cycle() -> None:
    """A review's run: inject 8, a refused reset, a power cycle, enable."""
    sim = make_sim()
    drive = sim.drive
    drive.apply("inject_alarm", {"code": POSITION_SENSOR})
    sim.w(0, 0x08)
    sim.w(0, 0x00)
    assert drive.read_register(46) == POSITION_SENSOR  # refused: the cause is there
    sim.events.clear()
    _power_cycle(sim)
    assert drive.state is State.FAULT
    assert drive.read_register(46) == POSITION_SENSOR
    assert drive.error_code() == 0x7300
    assert drive.display == " 8"
    # ended with the power (the display goes dark), found again by the self test
    assert [(e["code"], e["active"]) for e in sim.kinds("alarm")] == [("8", False), ("8", True)]
    sim.w(0, 0x03)
    sim.run(5)
    assert drive.state is State.FAULT  # no torque
    sim.w(0, 0x0B)
    sim.w(0, 0x03)
    assert drive.read_register(46) == POSITION_SENSOR  # the reset is still refused
    drive.apply("clear_alarm", {"code": POSITION_SENSOR})
    sim.w(0, 0x0B)
    sim.w(0, 0x03)
    sim.run(5)
    assert drive.read_register(46) == 0
    assert drive.state is State.SWITCH_ON_DISABLED  # Ten_cmd held through the reset
    sim.w(0, 0x00)
    sim.w(0, 0x03)
    assert drive.state is State.OPERATION_ENABLED


def test_a_cleared_cause_does_not_come_back() -> None:
    sim = make_sim()
    sim.drive.apply("inject_alarm", {"code": POSITION_SENSOR})
    sim.drive.apply("clear_alarm", {"code": POSITION_SENSOR})  # still latched, cause gone
    _power_cycle(sim)
    assert sim.drive.read_register(46) == 0
    assert sim.drive.state is State.SWITCH_ON_DISABLED


def test_an_event_alarm_does_not_come_back() -> None:
    """A limit switch alarm (20) has no lasting cause: a power cycle clears it."""
    sim = make_sim()
    sim.run_into_ls1()
    sim.events.clear()
    _power_cycle(sim)
    assert [(e["code"], e["active"]) for e in sim.kinds("alarm")] == [("20", False)]
    assert sim.drive.read_register(46) == 0
    assert sim.drive.state is State.SWITCH_ON_DISABLED


def test_two_injected_causes_come_back_in_their_order() -> None:
    sim = make_sim()
    sim.drive.apply("inject_alarm", {"code": 24})
    sim.drive.apply("inject_alarm", {"code": 7})
    _power_cycle(sim)
    assert sim.drive.alarms.latched == [24, 7]
    assert sim.drive.read_register(46) == 24


def test_a_condition_the_model_sees_going_leaves_an_injected_cause() -> None:
    """The CoE slave's mapping cause (alarm 33) goes when a valid mapping passes PREOP ->
    SAFEOP; an injected 33 stands until clear_alarm, as every injected cause does."""
    table = alarm_table("ethercat")
    seen, injected = AlarmBank.empty(), AlarmBank.empty()
    seen.latch(33, lasting_cause=True)
    injected.latch(33, lasting_cause=True, injected=True)
    for bank in (seen, injected):
        bank.condition_gone(33)
    assert (seen.causes, seen.reset(table), seen.latched) == (set(), [33], [])
    assert (injected.reset(table), injected.latched, injected.injected_causes()) == ([], [33], [33])
    injected.remove_cause(33)  # clear_alarm
    assert (injected.reset(table), injected.injected_causes()) == ([33], [])
