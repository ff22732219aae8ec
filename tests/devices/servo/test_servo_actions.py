"""Operator and scenario actions: declared as data, range-checked, expressed through the same
state a fieldbus master changes, and the events they produce (the foundation's schema)."""

from __future__ import annotations

import pytest
from servo_helpers import make_sim

from devices.device import CommandError
from devices.servo.drive import ServoDrive
from devices.servo.ds402 import State


def test_every_action_has_a_handler() -> None:
    for name in ServoDrive.ACTIONS:
        assert callable(getattr(ServoDrive, f"cmd_{name}"))
    assert ServoDrive.KIND == "servo"


@pytest.mark.parametrize(("action", "args"), [
    ("write_register", {"register": 134, "value": 0}),
    ("write_register", {"register": 9, "value": 1 << 32}),
    ("write_register", {"register": 5, "value": 0}),
    ("write_register", {"register": 4, "value": 0x2000}),
    ("write_parameter", {"parameter": "d1", "value": 0}),
    ("write_parameter", {"parameter": "zz", "value": 1}),
    ("write_parameter", {"parameter": "o1", "value": 1}),
    ("control_register", {"value": 0x10000}),
    ("controlword", {"value": -1}),
    ("set_mode", {"mode": 2}),
    ("set_input", {"name": "pin99", "value": True}),
    ("inject_alarm", {"code": 17}),
    ("jog", {"direction": 2}),
    ("analog_input", {"volts": 10.5}),
    ("write_object", {"index": 0x6041, "sub": 0, "value": 1}),
    ("write_object", {"index": 0x6066, "sub": 0, "value": 0x2000}),
    ("move", {"position": 1 << 31}),
    ("no_such_action", {}),
])
def test_bad_commands_are_refused_and_change_nothing(action: str, args: dict) -> None:
    from devices.od import SdoAbort
    sim = make_sim()
    before = sim.drive.snapshot()
    with pytest.raises((CommandError, SdoAbort)):
        sim.drive.apply(action, args)
    assert sim.drive.snapshot() == before


def test_parameters_by_name_or_number() -> None:
    sim = make_sim()
    sim.drive.apply("write_parameter", {"parameter": "d3", "value": 10})
    assert sim.drive.apply("read_parameter", {"parameter": 3}) == 10
    assert sim.drive.apply("read_parameter", {"parameter": "0x0003"}) == 10


def test_enable_move_stop_and_alarm_reset() -> None:
    sim = make_sim()
    d = sim.drive
    d.apply("enable", {"on": True})
    assert d.read_register(0) == 0x03 and d.state is State.OPERATION_ENABLED
    d.apply("move", {"position": 12000})
    sim.run(500)
    d.apply("stop", {})
    assert d.read_register(0) & 0x04  # Stp_cmd
    sim.run(1)
    assert d.read_register(5) & 0x04  # Stp_st: stop ramp running
    sim.run(300)
    assert d.read_register(8) == 0
    stopped_at = d.position_user
    assert 0 < stopped_at < 12000
    d.apply("move", {"position": 3000, "relative": True})  # clears Stp_cmd; from where it stands
    sim.run_until(lambda: d.read_register(5) & 0x40, 5_000)
    sim.run(20)
    assert d.position_user == stopped_at + 3000
    d.apply("inject_alarm", {"code": "MOTOR_CURRENT"})
    d.apply("clear_alarm", {"code": 3})
    d.apply("alarm_reset", {})
    assert d.read_register(46) == 0
    # Ten_cmd held through the reset enables nothing (test_servo_reenable.py); Enable does
    assert d.state is State.SWITCH_ON_DISABLED
    d.apply("enable", {"on": True})
    assert d.read_register(0) == 0x03 and d.state is State.OPERATION_ENABLED


def test_jog_and_home() -> None:
    sim = make_sim()
    d = sim.drive
    d.apply("enable", {"on": True})
    d.apply("jog", {"direction": 1})
    assert d.mode == 3 and d.read_register(13) == d.read_register(12)
    sim.run(500)
    assert d.read_register(8) == 1000
    d.apply("jog", {"direction": 0})
    sim.run(100)
    d.apply("home", {})
    assert d.mode == 6
    sim.run_until(lambda: d.read_register(5) & 0x40, 10_000, tick_ms=10)
    assert d.homed


def test_jog_on_a_disabled_drive_says_why_it_does_not_move() -> None:
    """Jog sets mode 3 and R13 as a master's writes would, also without torque (the writes are
    accepted, ch. 2), and the axis stays: the action's answer says why, for the panel."""
    sim = make_sim()
    d = sim.drive
    assert d.state is State.SWITCH_ON_DISABLED
    assert d.apply("jog", {"direction": 1}) == \
        "not enabled (Switch on disabled) - enable torque first"
    assert d.mode == 3 and d.read_register(13) == d.read_register(12)
    sim.run(200)
    assert d.read_register(8) == 0  # no motion
    assert d.apply("jog", {"direction": 0}) is None  # a stop needs no notice
    d.apply("enable", {"on": True})
    assert d.apply("jog", {"direction": 1}) is None
    d.apply("inject_alarm", {"code": "MOTOR_CURRENT"})
    assert d.state is State.FAULT
    assert d.apply("jog", {"direction": -1}) == \
        "not enabled (Fault, alarm 3) - reset the alarm, then enable torque"


def test_events_follow_the_schema() -> None:
    sim = make_sim()
    sim.drive.apply("enable", {"on": True})
    sim.drive.apply("inject_alarm", {"code": 16})
    sim.run(1)
    records = [e.to_record() for e in sim.events]
    kinds = {r["event"] for r in records}
    assert {"state", "alarm", "log"} <= kinds
    for r in records:
        assert set(r) >= {"t", "device", "event"} and r["device"] == "servo"
    alarm = next(r for r in records if r["event"] == "alarm")
    assert alarm == {"t": alarm["t"], "device": "servo", "event": "alarm", "code": "16",
                     "name": "FOLLOWING_ERROR", "active": True}


def test_a_powered_off_drive_refuses_commands_but_not_power_or_wiring() -> None:
    sim = make_sim()
    d = sim.drive
    d.apply("power", {"on": False})
    for action, args in (("enable", {"on": True}), ("read_register", {"register": 6}),
                         ("inject_alarm", {"code": 1})):
        with pytest.raises(CommandError):
            d.apply(action, args)
    d.apply("set_input", {"name": "ten", "value": False})
    d.apply("power", {"on": True})
    sim.run(60)
    d.apply("enable", {"on": True})
    assert d.state is State.SWITCHED_ON  # TEN is not wired any more


def test_snapshot_has_the_agreed_keys() -> None:
    snap = make_sim().drive.snapshot()
    for key in ("kind", "id", "powered", "fieldbus", "node_id", "ds402_state", "controlword",
                "statusword", "control_register", "status_register", "status_bits", "mode",
                "mode_name", "position", "position_counts", "velocity", "following_error",
                "target", "ten", "ien", "inputs", "outputs", "alarm", "display", "saving",
                "homed", "limits", "axis"):
        assert key in snap
    assert snap["kind"] == "servo" and snap["display"] == "Fr"
    import json
    json.dumps(snap)


def test_move_after_homing_starts() -> None:
    """After homing R00 still holds bit 6 (the homing start); in mode 1 that bit reads as the
    same new-set-point bit as the start, so ``move`` must clear it first to give an edge."""
    sim = make_sim()
    d = sim.drive
    d.apply("enable", {"on": True})
    d.apply("home", {})
    sim.run_until(lambda: d.homed, 30_000, tick_ms=10)
    d.apply("move", {"position": 6000})
    sim.run_until(lambda: d.read_register(6) == 6000, 30_000, tick_ms=10)
