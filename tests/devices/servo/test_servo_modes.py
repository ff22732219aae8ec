"""Modes of operation (R01 / 0x6060), with the seed 004 ch. 4 worked examples where there are
some and the ch. 2 "I/O digitali" rules for Start, Select and End of Job."""

from __future__ import annotations

import pytest
from servo_helpers import CANOPEN_ENABLE, Sim, make_sim

from devices.servo import ds402
from devices.servo.drive import DriveConfig

EOJ = 0x40


def _od(sim: Sim, *writes: tuple[int, int, int]) -> None:
    for index, sub, value in writes:
        sim.drive.od.write(index, sub, value)


def test_positioner_canopen_example_incremental_then_absolute() -> None:
    """Ch. 4 "Modo posizionatore": 200 rpm, 100 ms ramps, +10 turns then 5 turns absolute."""
    sim = make_sim()
    _od(sim, (0x6092, 1, 6000), (0x6081, 0, 20000), (0x6083, 0, 200), (0x6084, 0, 200),
        (0x6060, 0, 1))
    sim.cw(*CANOPEN_ENABLE)
    _od(sim, (0x607A, 0, 60000))
    sim.cw(0x004F, 0x005F)
    assert sim.drive.statusword & ds402.SW_MODE_12  # set-point acknowledged
    sim.run(100)  # "100 ms per passare da 0 a 200 r.p.m."
    assert sim.drive.read_register(73) == pytest.approx(200, abs=3)
    took = sim.run_until(lambda: sim.drive.statusword & ds402.SW_TARGET_REACHED, 5_000)
    assert took == pytest.approx(3000, abs=30)  # 10 turns at 200 rpm + one ramp
    sim.run(20)
    assert sim.drive.od.read(0x6064, 0) == 60000
    _od(sim, (0x607A, 0, 30000))
    sim.cw(0x000F, 0x001F)
    sim.run_until(lambda: sim.drive.statusword & ds402.SW_TARGET_REACHED, 5_000)
    sim.run(20)
    assert sim.drive.od.read(0x6064, 0) == 30000


def _positioner(sim: Sim, target: int = 60000) -> None:
    sim.w(12, 20000)
    sim.w(10, 200)
    sim.w(11, 200)
    sim.w(0, 0x03)
    sim.w(9, target)


def test_positioner_buffers_a_set_point_without_update_on_the_fly() -> None:
    """Upd_mod = 0: the new set-point waits for the end of the move (sp_rdy = 0 meanwhile)."""
    sim = make_sim()
    _positioner(sim)
    sim.w(0, 0x23)
    sim.run(500)
    sim.w(9, 10000)
    sim.w(0, 0x23)
    assert sim.r05 & 0x20 == 0  # sp_rdy: the buffer is full
    sim.run_until(lambda: sim.drive.position_user >= 59_999, 5_000)
    sim.run_until(lambda: sim.r05 & EOJ, 5_000)
    sim.run(20)
    assert sim.drive.position_user == 10000
    assert sim.r05 & 0x20


def test_positioner_updates_the_set_point_on_the_fly() -> None:
    """Upd_mod = 1 (R00 bit 6): the axis turns round at once and never reaches 60000."""
    sim = make_sim()
    _positioner(sim)
    sim.w(0, 0x23)
    sim.run(500)
    sim.w(9, 10000)
    sim.w(0, 0x63)
    peak = 0
    while not sim.r05 & EOJ:
        sim.run(5)
        peak = max(peak, sim.drive.position_user)
    sim.run(20)
    assert peak < 20000
    assert sim.drive.position_user == 10000


def test_incremental_set_points_add_up() -> None:
    """Inc_mod (R00 bit 7): each start moves by R09 from the previous target."""
    sim = make_sim()
    _positioner(sim, target=1500)
    for _ in range(3):
        sim.w(0, 0xA3)
        sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == 4500


def test_select_input_takes_aux_in_1_and_start_input_starts() -> None:
    """Select high: the target is R30 aux_in_1; the Start input's rising edge starts (ch. 2)."""
    sim = make_sim()
    _positioner(sim)
    sim.w(30, -2500)
    sim.drive.apply("set_input", {"name": "select", "value": True})
    sim.drive.apply("set_input", {"name": "start", "value": True})
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == -2500


@pytest.mark.parametrize("profile", [0, -1, -2])
def test_profiles_reach_the_target_with_the_same_ramp_time(profile: int) -> None:
    """R27 / 0x6086: 0 trapezoidal, -1 S, -2 sine; the mean ramp acceleration is R10."""
    sim = make_sim()
    sim.w(27, profile)
    _positioner(sim, target=30000)
    sim.w(0, 0x23)
    sim.run(100)
    assert sim.drive.trajectory.velocity * 6000 == pytest.approx(20000, rel=1e-6)
    took = sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    assert took == pytest.approx(1500 + 100 - 101, abs=10)
    sim.run(20)
    assert sim.drive.position_user == 30000


def test_profile_velocity_0_does_not_move_the_axis() -> None:
    """R12 profile_velocity = 0 (its printed range starts at 0, ch. 1): no speed allowed, so
    a start leaves the axis where it stands, without End of Job; with R12 back it moves."""
    sim = make_sim()
    _positioner(sim, target=30000)
    sim.w(12, 0)
    sim.w(0, 0x23)
    sim.run(500)
    assert sim.drive.position_user == 0 and sim.drive.read_register(8) == 0
    assert not sim.r05 & EOJ and not sim.drive.outputs()["end_of_job"]
    assert sim.drive.alarms.latched == []
    sim.w(12, 20000)
    sim.w(0, 0x23)
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == 30000


def test_near_to_target_output() -> None:
    """Out 3 "Near to target": low at the start, high within target_window (R61)."""
    sim = make_sim()
    sim.w(61, 1000)
    _positioner(sim, target=30000)
    sim.w(0, 0x23)
    assert not sim.drive.outputs()["near_target"]
    sim.run_until(lambda: sim.drive.outputs()["near_target"], 3_000)
    assert 29_000 <= sim.drive.position_user < 30000
    assert not sim.drive.outputs()["end_of_job"]


@pytest.mark.parametrize("after", [0x00, 0x07, 0x01])  # torque off, Stp_cmd, Ien_cmd off
def test_near_to_target_is_lowered_only_by_a_start(after: int) -> None:
    """"Allo start del posizionamento quest'uscita viene abbassata" (ch. 2, Target): nothing
    else lowers it. The axis standing at its target keeps the output high when torque goes
    off, a stop is commanded or motion is disabled, and when torque comes back; the next start
    lowers it."""
    sim = make_sim()
    sim.w(61, 1000)
    _positioner(sim, target=30000)
    sim.w(0, 0x23)
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.outputs()["near_target"]
    sim.w(0, after)
    sim.run(50)
    assert sim.drive.outputs()["near_target"]
    sim.w(0, 0x03)
    sim.run(50)
    assert sim.drive.outputs()["near_target"]
    sim.w(9, 60000)
    sim.w(0, 0x23)
    assert not sim.drive.outputs()["near_target"]


def test_velocity_canopen_example() -> None:
    """Ch. 4 "Modo controllo di velocità": feed 60, 200 ms from 0 to 1000 rpm."""
    sim = make_sim()
    _od(sim, (0x6092, 1, 60), (0x6083, 0, 5), (0x6084, 0, 5), (0x6060, 0, 3))
    sim.cw(*CANOPEN_ENABLE)
    _od(sim, (0x60FF, 0, 1000))
    sim.run(100)
    assert sim.drive.read_register(73) == pytest.approx(500, abs=15)  # 2 ms behind
    assert not sim.drive.outputs()["end_of_job"]
    sim.run(110)
    assert sim.drive.read_register(73) == 1000
    assert sim.drive.outputs()["end_of_job"]  # target speed of the generator reached
    sim.run(20)
    assert sim.drive.statusword & ds402.SW_TARGET_REACHED  # velocity window


def test_velocity_select_and_zero_speed() -> None:
    """Select picks aux_in_1 (R30); R05 bit 7 "velocità nulla" after the threshold time."""
    sim = make_sim()
    sim.w(1, 3)
    sim.w(30, 3000)
    sim.w(13, 600)
    sim.w(0, 0x03)
    sim.run(200)
    assert sim.drive.read_register(8) == pytest.approx(600, abs=2)
    assert sim.r05 & 0x80 == 0
    sim.drive.apply("set_input", {"name": "select", "value": True})
    sim.run(300)
    assert sim.drive.read_register(8) == pytest.approx(3000, abs=2)
    sim.w(30, 0)
    sim.run(300)
    assert sim.r05 & 0x80
    assert sim.drive.statusword & ds402.SW_MODE_12


ZERO_SPEED = 0x80  # R05 bit 7 in the velocity modes 3 and -127


def _zero_speed(sim: Sim) -> bool:
    """R05 bit 7 and 0x6041 bit 12 must agree in both velocity modes: -127 is "modo
    riferimento analogico velocità" (seed 004 ch. 4), speed control from the analog input, so
    R05 bit 7 "Controllo Velocità: velocità nulla" applies to it (docs/servo-drive.md)."""
    assert sim.drive.mode in (3, -127)
    twin = bool(sim.drive.statusword & ds402.SW_MODE_12)
    assert bool(sim.r05 & ZERO_SPEED) is twin
    assert sim.drive.snapshot()["status_bits"]["Zero_velocity"] is twin
    return twin


@pytest.mark.parametrize("stop_cw", [0x07, 0x01, 0x00], ids=["Stp_cmd", "Ien_cmd off",
                                                             "torque off"])
@pytest.mark.parametrize("mode", [3, -127])
def test_zero_speed_reports_the_axis_standing_whatever_stopped_it(stop_cw: int,
                                                                  mode: int) -> None:
    """Ch. 1 R05 bit 7, "Controllo Velocità: velocità nulla: 1: asse fermo": the axis, not the
    command. An axis stopped from speed by Stp_cmd, Ien_cmd off or torque off (coasting) reports
    it once its speed has stayed within R16 for R17 = 10 ms, and so does 0x6041 bit 12."""
    sim = make_sim()
    sim.w(1, mode)
    sim.w(13, 1000)
    sim.drive.apply("analog_input", {"volts": 2.0})
    sim.w(0, 0x03)
    sim.run(500)
    assert abs(sim.drive.read_register(8)) > 100
    assert not _zero_speed(sim)
    sim.w(0, stop_cw)
    threshold = sim.drive.read_register(16)  # R16 velocity_threshold (default 100)
    sim.run_until(lambda: abs(sim.drive.velocity_user) <= threshold, 5_000)
    sim.run(9)
    assert not _zero_speed(sim)  # within the threshold for less than R17 so far
    sim.run(2)
    assert _zero_speed(sim)
    sim.w(0, 0x00)  # torque off at a standstill: still standing
    sim.run(50)
    assert _zero_speed(sim)


def test_zero_speed_without_torque_in_mode_3() -> None:
    """Mode 3 selected, never in torque: the axis stands, so "asse fermo"."""
    sim = make_sim()
    sim.w(1, 3)
    sim.run(20)
    assert _zero_speed(sim)
    sim.w(0, 0x01)  # torque, no Ien_cmd
    sim.run(20)
    assert _zero_speed(sim)


def _homing_sim(start: float = 0.0, method: int = 34, offset: int = 0) -> Sim:
    cfg = DriveConfig(neg_limit=-18000, pos_limit=18000, home_switch=2400, marker_offset=1500,
                      start_position=start)
    sim = make_sim(cfg)
    for n, v in ((18, method), (19, offset), (20, 12000), (21, 3000), (22, 2000)):
        sim.w(n, v)
    return sim


def _home(sim: Sim) -> None:
    sim.w(1, 6)
    sim.w(0, 0x03)
    sim.w(0, 0x43)
    sim.run_until(lambda: sim.r05 & 0xC0, 20_000, tick_ms=5)


def test_homing_canopen_example_offset_minus_1000_reads_1000() -> None:
    """Ch. 4 "Modo Homing": method 34, offset -1000 -> "la posizione attuale varrà 1000"."""
    sim = make_sim()
    _od(sim, (0x6092, 1, 6000), (0x6098, 0, 34), (0x607C, 0, -1000),
        (0x6099, 2, 1000), (0x6060, 0, 6))
    sim.cw(*CANOPEN_ENABLE)
    sim.cw(0x000F, 0x001F)
    assert sim.drive.statusword & 0x3000 == 0  # not completed yet
    sim.run_until(lambda: sim.drive.statusword & 0x3000, 10_000)
    assert sim.drive.statusword & 0x3000 == 0x1000  # bit 12 = 1, bit 13 = 0: success
    assert sim.drive.od.read(0x6064, 0) == 1000
    assert sim.drive.plant.theta == pytest.approx(0.25, abs=0.5 / 6000)  # the first marker above 0
    sim.cw(0x000F)
    assert sim.drive.state.label == "Operation enabled"  # "l'asse rimane fermo in coppia"


# method -> {carriage start: home point}, in rig units: limits at -18000 / 18000, home switch
# active from 2400 up, markers at 1500 + k * 6000
HOME_POINTS: dict[int, dict[float, float]] = {
    1: {0: -16500, 5000: -16500},  # first marker above the negative limit switch
    2: {0: 13500, 5000: 13500},  # first marker below the positive limit switch
    3: {0: 1500, 5000: 1500},  # the marker below the home switch edge
    4: {0: 7500, 5000: 7500},  # the marker above the edge
    17: {0: -18000, 5000: -18000},
    18: {0: 18000, 5000: 18000},
    19: {0: 2400, 5000: 2400},
    20: {0: 2400, 5000: 2400},
    33: {0: -4500, 5000: 1500},
    34: {0: 1500, 5000: 7500},
    35: {0: 0, 5000: 5000},
}


@pytest.mark.parametrize("method", sorted(HOME_POINTS))
@pytest.mark.parametrize("start", [0.0, 5000.0])
def test_homing_methods(method: int, start: float) -> None:
    """Supported methods (docs/servo-drive.md §Homing) find their home point from either side
    of the home switch, and the home point reads -home_offset."""
    sim = _homing_sim(start=start, method=method, offset=-250)
    _home(sim)
    assert sim.r05 & 0xC0 == 0x40, "Homing ok, no homing error"
    assert sim.drive.plant.theta * 6000 == pytest.approx(HOME_POINTS[method][start], abs=0.5)
    assert sim.drive.position_user == 250
    assert sim.drive.homed and sim.drive.outputs()["end_of_job"]


def test_homing_method_33_modbus_example() -> None:
    """Ch. 2 example: method 0x21 searches the marker in the negative direction."""
    sim = _homing_sim(method=33)
    _home(sim)
    assert sim.drive.plant.theta * 6000 == pytest.approx(-4500, abs=0.5)
    assert sim.drive.position_user == 0


def test_unsupported_homing_method_is_a_homing_error() -> None:
    sim = _homing_sim(method=7)
    _home(sim)
    assert sim.r05 & 0x80  # homing error
    assert sim.drive.read_register(46) == 14
    assert sim.drive.statusword & 0x3000 == 0x2000


def test_homing_interrupted_by_clearing_the_start_bit() -> None:
    """Bit 12 = 0, bit 13 = 1: "homing interrotto" (ch. 4)."""
    sim = _homing_sim(method=33)
    sim.w(1, 6)
    sim.w(0, 0x03)
    sim.w(0, 0x43)
    sim.run(200)
    sim.w(0, 0x03)
    assert sim.drive.statusword & 0x3000 == 0x2000
    assert sim.drive.read_register(46) == 0  # interrupted, not an alarm


def test_homing_past_a_limit_switch_it_does_not_search_runs_into_the_end_stop() -> None:
    """Method 3 (home switch) with the home switch beyond LS2: for this method pin 9 is a
    digital input (seed 004 ch. 2 l. 1488-1494), so the search goes on to the mechanical end
    stop and the following error (alarm 16) ends it. It used to fail at LS2 with alarm 14."""
    cfg = DriveConfig(neg_limit=-18000, pos_limit=18000, home_switch=30000)
    sim = make_sim(cfg)
    for n, v in ((18, 3), (20, 12000), (22, 1000)):
        sim.w(n, v)
    _home(sim)
    assert sim.drive.read_register(46) == 16
    assert sim.drive.read_register(48) & 1 << 9


@pytest.mark.parametrize(("method", "fast", "slow"), [
    (18, 1_000_000, 3000), (17, 1_000_000, 3000), (1, 12000, 1_000_000)],
    ids=["18 fast", "17 fast", "1 slow"])
def test_homing_speeds_are_limited_by_d3(method: int, fast: int, slow: int) -> None:
    """Ch. 1 "d3 Velocità massima del motore, Vmax %": d3 limits every speed, homing's too
    (R20 fast, R21 slow). 1e6 user units/s at feed 6000 is 10000 rpm; d3 = 50 % of 3000 rpm
    is 1500 rpm. Unclamped, the search ran at 6000 rpm and tripped alarm 16."""
    sim = _homing_sim(method=method)
    sim.w(20, fast)
    sim.w(21, slow)
    sim.w(22, 20_000)  # 0.1 turn to Vmax: short searches reach it too
    d = sim.drive
    vmax_rpm = d.motor_vmax_rev * 60
    assert vmax_rpm == pytest.approx(1500)
    sim.w(1, 6)
    sim.w(0, 0x03)
    sim.w(0, 0x43)
    peak = 0.0
    while not sim.r05 & 0xC0:
        assert sim.t_us < 30_000_000, "homing did not end"
        sim.run(1)
        peak = max(peak, abs(d.trajectory.velocity) * 60, abs(d.plant.omega) * 60)
    assert peak == pytest.approx(vmax_rpm)  # at Vmax, not beyond
    assert sim.r05 & 0xC0 == 0x40, "Homing ok, no homing error"
    assert d.read_register(46) == 0
    assert d.plant.theta * 6000 == pytest.approx(HOME_POINTS[method][0], abs=0.5)


def test_interpolator_follows_a_set_point_per_period() -> None:
    """Mode 7: 0x60C2:1 = 2 ms; each period the drive takes 0x60C1:1 and moves linearly."""
    sim = make_sim()
    _od(sim, (0x60C2, 1, 2), (0x6060, 0, 7))
    sim.cw(*CANOPEN_ENABLE)
    sim.cw(0x001F)
    assert sim.drive.statusword & ds402.SW_MODE_12  # interpolator active
    for k in range(1, 501):
        _od(sim, (0x60C1, 1, 10 * k))
        sim.run(2)
    assert sim.drive.trajectory.velocity * 6000 == pytest.approx(5000)  # 10 units / 2 ms
    sim.run(50)
    assert sim.drive.position_user == 5000
    sim.cw(0x000F)
    assert not sim.drive.statusword & ds402.SW_MODE_12


def test_pulse_positioner_each_pulse_is_a_new_start() -> None:
    """Mode -1: R24 pulses per motor turn through R25 / R26; End of Job like the positioner."""
    sim = make_sim()
    sim.w(12, 6000)
    sim.w(24, 1000)
    sim.w(25, 2)
    sim.w(26, 1)
    sim.w(1, -1)
    sim.w(0, 0x03)
    sim.drive.apply("pulses", {"count": 250})
    assert sim.r05 & EOJ == 0
    sim.run_until(lambda: sim.r05 & EOJ, 3_000)
    sim.run(20)
    assert sim.drive.position_user == 3000  # 250 pulses * 6000 * 2 / 1000


def test_pulse_positioner_does_not_drive_near_to_target() -> None:
    """"L'uscita Target viene utilizzata con il posizionatore punto a punto (modes_of_operation
    = 1) e anche in modo posizionatore SAP" (ch. 2): mode -1 is neither, so pin 15 stays low
    there while End of Job works "del tutto simile al posizionatore"."""
    sim = make_sim()
    sim.w(61, 1000)
    sim.w(1, -1)
    sim.w(0, 0x03)
    sim.drive.apply("pulses", {"count": 4096})
    seen = False
    while not sim.r05 & EOJ:
        seen |= sim.drive.outputs()["near_target"]
        sim.run(5)
        assert sim.t_us < 20_000_000
    sim.run(20)
    assert sim.drive.position_user == 6000 and sim.drive.outputs()["end_of_job"]
    assert not seen and not sim.drive.outputs()["near_target"]


def test_electronic_axis_follows_the_master_when_started() -> None:
    """Mode -2: locked to the master with the Start input high and the start bit (ch. 2)."""
    sim = make_sim()
    sim.w(25, 2)
    sim.w(26, 1)
    sim.w(1, -2)
    sim.drive.apply("master_encoder", {"rpm": 300.0})
    sim.w(0, 0x43)
    sim.run(100)
    assert sim.drive.read_register(73) == 0  # Start input low: held in torque
    sim.drive.apply("set_input", {"name": "start", "value": True})
    sim.run(100)
    assert sim.drive.read_register(73) == 600
    assert sim.r05 & 0x40  # axis started
    assert sim.drive.read_register(23) == round(300 / 60 * 4096 / 1000)
    assert not sim.drive.outputs()["end_of_job"]  # always low in mode -2


@pytest.mark.parametrize("r00", [0x23, 0x43])
def test_electronic_axis_starts_with_r00_bit_5_or_bit_6(r00: int) -> None:
    """Ch. 1 puts the electronic axis' Start/stop at R00 bit 6, ch. 2 "I/O digitali" says "il
    bit 5 di ControlWord": either engages with the Start input high (docs/servo-drive.md, mode
    -2), and neither without it; R05 bit 6 and 0x6040 bit 11 say the same."""
    sim = make_sim()
    sim.w(1, -2)
    sim.drive.apply("master_encoder", {"rpm": 300.0})
    sim.w(0, r00)
    sim.run(100)
    assert sim.drive.read_register(73) == 0 and not sim.r05 & 0x40
    sim.drive.apply("set_input", {"name": "start", "value": True})
    sim.run(100)
    assert sim.drive.read_register(73) == 300 and sim.r05 & 0x40
    assert sim.drive.cw & ds402.CW_AXIS_START
    sim.w(0, 0x03)
    sim.run(1)
    assert not sim.r05 & 0x40 and not sim.drive.cw & ds402.CW_AXIS_START


def test_the_motor_never_turns_faster_than_vmax_in_the_electronic_axis() -> None:
    """d3 "Velocità massima del motore, Vmax %" (ch. 1) is the motor's limit, whatever the
    mode: a master too fast for the gear ratio (1000 rpm x 2 with Vmax = 50 % of 3000 rpm)
    leaves the motor at 1500 rpm, the following error grows and alarm 16 releases the axis
    ("superato per un tempo superiore al timeout", ch. 3)."""
    sim = make_sim()
    assert sim.drive.motor_vmax_rev * 60 == pytest.approx(1500)
    sim.w(25, 2)
    sim.w(1, -2)
    sim.w(0, 0x43)
    sim.drive.apply("master_encoder", {"rpm": 1000.0})
    sim.drive.apply("set_input", {"name": "start", "value": True})
    top = 0
    while sim.drive.read_register(46) != 16:
        sim.run(1)
        top = max(top, sim.drive.read_register(73))
        assert sim.t_us < 2_000_000, "no following-error alarm"
    assert top <= 1500


def test_save_load_mode_loads_from_flash() -> None:
    """Mode -50: bit 5 saves, bit 6 0 -> 1 loads registers and parameters (R05 bit 6)."""
    sim = make_sim()
    sim.w(12, 1234)
    sim.w(1, -50)
    sim.w(0, 0x20)
    sim.run_until(lambda: sim.drive.responding, 5_000)
    sim.w(12, 999)
    sim.w(0, 0x00)
    sim.w(0, 0x40)
    assert sim.drive.read_register(12) == 1234
    assert sim.r05 & 0x40
    assert sim.drive.mode == -50


def test_analog_reference() -> None:
    """Mode -127: +-10 V is +-Vmax (d3 % of the motor speed); End of Job always low."""
    sim = make_sim()
    sim.w(1, -127)
    sim.drive.apply("analog_input", {"volts": 5.0})
    sim.w(0, 0x03)
    sim.run(1000)
    assert sim.drive.read_register(73) == 750  # 3000 rpm * 50 % * 5 V / 10 V
    assert not sim.drive.outputs()["end_of_job"]


def test_canopen_full_example_homing_then_interpolator() -> None:
    """Ch. 4 "Esempio completo di asse gestito con interpolatore" (without the PDO set-up)."""
    sim = make_sim()
    od = sim.drive.od
    _od(sim, (0x6092, 1, 6000), (0x60C2, 1, 1), (0x6098, 0, 34), (0x607C, 0, -1000),
        (0x6099, 2, 1000))
    for value, address in ((80, 1), (20, 2)):  # d1 = 80, d2 = 20 through 0x2000
        _od(sim, (0x2000, 2, value), (0x2000, 1, address))
        sim.run_until(lambda: od.read(0x2000, 1) == 0, 100)
    assert (sim.drive.read_parameter(1), sim.drive.read_parameter(2)) == (80, 20)
    sim.cw(*CANOPEN_ENABLE)
    _od(sim, (0x6060, 0, 6))
    sim.cw(0x001F)
    sim.run_until(lambda: sim.drive.statusword & 0x3000, 10_000)
    sim.cw(0x000F)  # "L'asse rimane fermo in coppia"
    assert sim.drive.position_user == 1000 and sim.drive.state.label == "Operation enabled"
    _od(sim, (0x6060, 0, 7))
    sim.cw(0x001F)
    for k in range(1, 1001):  # 1 ms period: +6 units per ms = 1 turn/s, for 1 s
        _od(sim, (0x60C1, 1, 1000 + 6 * k))
        sim.drive.apply("sync", {})
        sim.run(1)
    assert sim.drive.read_register(73) == 60
    sim.run(10)
    assert sim.drive.position_user == 7000
    sim.cw(0x000F)  # normal stop: interpolator off, held in torque
    sim.run(10)
    assert sim.drive.state.label == "Operation enabled" and sim.drive.read_register(8) == 0
    sim.cw(0x0002)  # release
    sim.run(10)
    assert sim.drive.read_register(5) & 0x01 == 0
