"""CiA 402 state machine (DSP 402 v1.1, referenced by seed 004 ch. 4), one test per transition.

Every entry of ``ds402.TRANSITIONS`` is driven on a real drive: bring it to the source state,
give the command the way a master (0x6040) or the world (alarm, TEN input, standstill) does,
and check the new state both in the model and as the statusword decodes it.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo import control, ds402
from devices.servo.ds402 import TRANSITIONS, Command, State
from devices.servo.plant import STOPPED_REV_S

C = Command


def _moving(sim: Sim) -> None:
    """Operation enabled and running in velocity mode, so that stops take time."""
    sim.drive.write_register(1, 3)
    sim.drive.write_register(13, 20_000)
    sim.cw(*CANOPEN_ENABLE)
    sim.run(150)


def _to(state: State) -> Callable[[Sim], None]:
    def setup(sim: Sim) -> None:
        if state is State.NOT_READY_TO_SWITCH_ON:
            return
        sim.run(60)
        if state is State.SWITCH_ON_DISABLED:
            return
        if state is State.READY_TO_SWITCH_ON:
            sim.cw(0x06)
        elif state is State.SWITCHED_ON:
            sim.cw(0x06, 0x07)
        elif state is State.OPERATION_ENABLED:
            sim.cw(*CANOPEN_ENABLE)
        elif state is State.QUICK_STOP_ACTIVE:
            _moving(sim)
            sim.drive.write_controlword(0x02)  # "release axis" (ch. 4) while running
        elif state is State.FAULT_REACTION_ACTIVE:
            _moving(sim)
            sim.drive.apply("inject_alarm", {"code": 5})  # no "released": stops on the ramp
        elif state is State.FAULT:
            sim.drive.apply("inject_alarm", {"code": 1})
            sim.drive.apply("clear_alarm", {"code": 1})
    return setup


CONTROLWORD = {C.SHUTDOWN: 0x06, C.SWITCH_ON: 0x07, C.ENABLE_OPERATION: 0x0F,
               C.DISABLE_VOLTAGE: 0x00, C.QUICK_STOP: 0x02}


def _trigger(sim: Sim, command: Command) -> None:
    d = sim.drive
    if command in CONTROLWORD:
        d.write_controlword(CONTROLWORD[command])
    elif command is C.FAULT_RESET:
        d.write_controlword(0x00)
        d.write_controlword(0x80)
    elif command is C.SELF_TEST_DONE:
        sim.run(60)
    elif command is C.FAULT:
        d.apply("inject_alarm", {"code": 1})
    elif command in (C.STANDSTILL, C.FAULT_REACTION_DONE):
        # standstill: the demand at rest and the motor, which lags it, stopped too
        sim.run_until(lambda: d.trajectory.idle and d.trajectory.velocity == 0.0
                      and d.plant.standstill, timeout_ms=2_000)
    elif command is C.TORQUE_LOST:
        d.apply("set_input", {"name": "ten", "value": False})


@pytest.mark.parametrize(("source", "command"), sorted(TRANSITIONS, key=lambda k: (
    TRANSITIONS[k][1], k[0].value, k[1].value)), ids=lambda v: getattr(v, "name", str(v)))
def test_transition(source: State, command: Command) -> None:
    target, number = TRANSITIONS[(source, command)]
    sim = make_sim(boot=False)
    _to(source)(sim)
    assert sim.drive.state is source
    _trigger(sim, command)
    # 0x000F from Ready to switch on is "switch on + enable operation": 3 then 4
    expected = State.OPERATION_ENABLED if (source, command) == (
        State.READY_TO_SWITCH_ON, C.ENABLE_OPERATION) else target
    if command is C.FAULT and source in (State.NOT_READY_TO_SWITCH_ON,
                                          State.SWITCH_ON_DISABLED, State.READY_TO_SWITCH_ON,
                                          State.SWITCHED_ON, State.OPERATION_ENABLED,
                                          State.QUICK_STOP_ACTIVE):
        expected = State.FAULT  # alarm 1 releases the axis at once: 13 then 14
    assert sim.drive.state is expected, f"transition {number}"
    assert ds402.state_of(sim.drive.statusword) is expected


@pytest.mark.parametrize(("controlword", "command"), [
    (0x0000, C.DISABLE_VOLTAGE), (0x0004, C.DISABLE_VOLTAGE), (0x0002, C.QUICK_STOP),
    (0x000B, C.QUICK_STOP), (0x0006, C.SHUTDOWN), (0x000E, C.SHUTDOWN),
    (0x0007, C.SWITCH_ON), (0x000F, C.ENABLE_OPERATION), (0x001F, C.ENABLE_OPERATION),
    (0x0080, None), (0x008F, None)])
def test_decode_controlword(controlword: int, command: Command | None) -> None:
    """DSP 402 device control commands (bits 0-3 and 7)."""
    assert ds402.decode(controlword) is command


@pytest.mark.parametrize("state", list(State))
def test_statusword_decodes_to_its_state(state: State) -> None:
    bits = ds402.STATE_BITS[state]
    assert ds402.state_of(bits) is state
    assert ds402.state_of(bits | ds402.SW_VOLTAGE_ENABLED | 0xFF00) is state


def test_fresh_drive_statusword_is_the_seeds_0x8640() -> None:
    """Ch. 6 Hilscher example: StatusWord = 0x8640 for a drive waiting to be enabled."""
    sim = make_sim()
    assert sim.drive.statusword == 0x8640


def test_ready_to_switch_on_reads_the_ch5_twincat_0x0621() -> None:
    """Ch. 5 "Settaggi SM / DC" (l. 4636-4638): a drive in mode 7 that a CiA 402 master put in
    Ready to switch on, TEN and IEN at 24 V, shows "Status Word 0x0621": bits 0, 5, 9, 10 and
    neither bit 4 "voltage enabled" nor bit 15 (docs/servo-drive.md §Status words)."""
    sim = make_sim()
    sim.w(1, 7)
    sim.cw(0x0000, 0x0006)
    assert sim.drive.state is State.READY_TO_SWITCH_ON
    assert sim.drive.statusword == 0x0621


def _bit15_case(case: str) -> Sim:
    sim = make_sim()
    if case.startswith("cia402"):
        sim.cw(0x0000, 0x0006)  # a CiA 402 master holds Ien_cmd (0x6040 has no bit for it)
    elif case.startswith("register"):
        sim.w(0, 0x03)
    low = case.rpartition(" ")[2]
    if low in ("ten", "ien"):
        sim.drive.apply("set_input", {"name": low, "value": False})
        sim.run(1)
    elif low == "off":
        sim.w(0, 0x00)
    elif low == "ien_cmd":
        sim.w(0, 0x01)  # Ten_cmd only: in torque, motion enable removed
    return sim


@pytest.mark.parametrize(("case", "forced"), [
    ("fresh", True),  # R00 = 0 at power-up: Ien_cmd low (ch. 6 Hilscher 0x8640)
    ("cia402 ready", False), ("cia402 ready ten", True), ("cia402 ready ien", True),
    ("register enabled", False), ("register enabled ien", True),
    ("register enabled ten", True), ("register enabled ien_cmd", True),
    ("register enabled off", True)])
def test_bit15_follows_ten_ien_and_ien_cmd_not_the_state(case: str, forced: bool) -> None:
    """Ch. 4 0x6041 bit 15: the target velocity is forced to 0 "quando l'asse viene
    disabilitato (segnale TEN basso) o quando viene tolta l'abilitazione al movimento
    (segnale IEN basso)"; Ien_cmd is R00's motion enable (ch. 1). Ready to switch on with
    both consents does not force it (ch. 5 0x0621)."""
    sim = _bit15_case(case)
    assert bool(sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO) is forced


def test_bit15_stays_clear_in_fault_with_the_consents_high() -> None:
    """Bit 15 names the signals, not the state: an alarm with TEN, IEN and Ien_cmd high."""
    sim = make_sim()
    sim.cw(*CANOPEN_ENABLE)
    sim.drive.apply("inject_alarm", {"code": 3})
    sim.run(50)
    assert sim.drive.state is State.FAULT
    assert not sim.drive.statusword & ds402.SW_VELOCITY_FORCED_ZERO


@pytest.mark.parametrize("state", list(State))
def test_voltage_enabled_from_switched_on(state: State) -> None:
    """Bit 4: DSP 402 "Switched on: high voltage has been applied"; Ready to switch on only
    "may" have it, and ch. 5's 0x0621 shows it clear there."""
    sw = control.cia402_status(control.StatusFlags(state=state, mode=1))
    powered = state in (State.SWITCHED_ON, State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE)
    assert bool(sw & ds402.SW_VOLTAGE_ENABLED) is powered


def test_canopen_enable_sequence_and_release() -> None:
    """Ch. 4: 0x0000, 0x0080, 0x0000, 0x0006, 0x0007, 0x000F gives torque; 0x0002 releases."""
    sim = make_sim()
    sim.cw(*CANOPEN_ENABLE)
    assert sim.drive.state is State.OPERATION_ENABLED
    assert sim.drive.read_register(5) & 0x03 == 0x03  # Ten_st, Ien_st
    sim.cw(0x0002)
    sim.run(5)
    assert sim.drive.state is State.SWITCH_ON_DISABLED
    assert [e["to"] for e in sim.kinds("state")][-2:] == ["Quick stop active",
                                                          "Switch on disabled"]


def test_strict_cia402_needs_shutdown_first() -> None:
    """0x000F from Switch on disabled is no DSP 402 command: nothing happens."""
    sim = make_sim()
    sim.cw(0x000F)
    assert sim.drive.state is State.SWITCH_ON_DISABLED


def test_register_view_ten_cmd_goes_into_torque_directly() -> None:
    """R00 = 3 (ch. 2 example) from Switch on disabled: transitions 2, 3, 4 at once."""
    sim = make_sim()
    sim.w(0, 0x03)
    assert [e["to"] for e in sim.kinds("state")][-3:] == [
        "Ready to switch on", "Switched on", "Operation enabled"]


def test_fault_reset_needs_a_rising_edge_and_no_cause() -> None:
    sim = make_sim()
    sim.cw(*CANOPEN_ENABLE)
    sim.drive.apply("inject_alarm", {"code": 8})
    assert sim.drive.state is State.FAULT
    sim.cw(0x0080, 0x0000, 0x0080)
    assert sim.drive.state is State.FAULT  # the injected cause is still there
    sim.drive.apply("clear_alarm", {"code": 8})
    sim.cw(0x0080)
    assert sim.drive.state is State.FAULT  # bit 7 held: no new edge
    sim.cw(0x0000, 0x0080)
    assert sim.drive.state is State.SWITCH_ON_DISABLED


@pytest.mark.parametrize("stop", ["quick stop", "alarm 2"])
def test_quick_stop_and_fault_reaction_end_with_the_motor_at_standstill(stop: str) -> None:
    """DSP 402 v1.1 (seed 004 ch. 4 "Device Profile: DSP 402 v1.1"): the quick stop and the
    fault reaction bring the axis to a standstill on the emergency ramp (F3 "Rampa di
    emergenza") before the torque goes off. The motor lags the demand (the position loop):
    ending when only the demand is at rest released a motor still turning at ~30 rpm, which
    then coasted ~600 user units with no control."""
    sim = make_sim()
    sim.cw(*CANOPEN_ENABLE)
    d = sim.drive
    d.od.write(0x6060, 0, 3)
    d.od.write(0x60FF, 0, 60000)  # 600 rpm at the default feed
    sim.run(1000)
    assert d.read_register(73) == 600
    ramp = State.QUICK_STOP_ACTIVE if stop == "quick stop" else State.FAULT_REACTION_ACTIVE
    if stop == "quick stop":
        d.write_controlword(0x000B)
    else:
        d.apply("inject_alarm", {"code": "2"})
    sim.run(1)
    assert d.state is ramp
    sim.run_until(lambda: d.state is not ramp, 2_000)
    assert d.state is (State.SWITCH_ON_DISABLED if stop == "quick stop" else State.FAULT)
    assert abs(d.plant.omega) < STOPPED_REV_S  # torque off only with the motor stopped
    released_at = d.position_user
    sim.run(2_000)
    assert abs(d.position_user - released_at) <= 1  # no coasting after the release
