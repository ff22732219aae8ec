"""The AX2 encoder module: seed 000 §6.11-§6.14, §6.26, §6.27, §6.30 and the codes 0x10..0x15
of §7.6."""

from __future__ import annotations

import random

import pytest

from devices.fastcat.catalog import CATALOG
from devices.fastcat.encoder import SUB
from devices.fastcat.modules import IoModule
from devices.od import ObjectDictionary

N = 2  # the module's position on the rail: objects at base + 0x10
POS, STATUS, CMD = 0x6510, 0x6610, 0x7610
PULSES, HOME, NO_COUNT_ALARM, DISABLE = 0x4010, 0x4011, 0x4012, 0x4013


def make(options=None, seed=0):
    module = IoModule(CATALOG["AX2"], random.Random(seed), options)
    od = ObjectDictionary()
    module.add_objects(od, N)
    return module, od


def run_ms(module, ms, dt_us=1000):
    for _ in range(ms):
        module.step(dt_us, True)


def spin(module, encoder, rpm):
    module.apply("set_shaft_speed", {"encoder": encoder, "rpm": rpm})


def pulses_after(t_us, rpm, ppr=2048):
    """Real pulse edges passed after t_us: the shaft starts half a pulse past a zero mark."""
    rate = round(rpm * ppr * SUB / 60)
    return (SUB // 2 + rate * t_us // 1_000_000) // SUB


@pytest.mark.parametrize("encoder", [1, 2])
def test_counts_per_revolution_at_default_2048(encoder):
    """§6.11: 2048 pulses/rev by default; one count per pulse (§6.26)."""
    m, od = make()
    spin(m, encoder, 60.0)  # one revolution per second
    run_ms(m, 1000)
    assert od.read(POS, encoder) == 2048
    assert od.read(POS, 3 - encoder) == 0
    assert m.take_raised_alarms() == []


def test_counts_per_revolution_at_a_set_0x4000():
    m, od = make({"encoder_ppr": [500, 2048]})
    od.write(PULSES, 1, 500)
    spin(m, 1, 120.0)
    run_ms(m, 5000)  # 10 revolutions, 10 zero marks checked
    assert od.read(POS, 1) == 5000
    assert m.take_raised_alarms() == []


@pytest.mark.parametrize(("command", "signs"), [
    (0x0000, (1, 1)), (0x0001, (-1, -1)), (0x4000, (-1, 1)), (0x8000, (1, -1)),
    (0xC000, (-1, -1)), (0x4001, (1, -1)),  # two inversions of one encoder cancel
])
def test_direction_inversion(command, signs):
    """§6.30: mask 0x0001 inverts both (printed 'Bit 1 (0x1)'), bit 14 enc 1, bit 15 enc 2."""
    m, od = make()
    od.write(CMD, 0, command)
    spin(m, 1, 30.0)
    spin(m, 2, 30.0)
    run_ms(m, 500)
    assert (od.read(POS, 1), od.read(POS, 2)) == (signs[0] * 512, signs[1] * 512)


def test_reverse_shaft_counts_down():
    m, od = make()
    spin(m, 1, -60.0)
    run_ms(m, 250)
    assert od.read(POS, 1) == -512


def test_position_preset_and_dint_rollover():
    """§6.26: position rw (preset); a DINT rolls over."""
    m, od = make()
    od.write(POS, 1, 0x7FFF_FFFF)
    spin(m, 1, 60.0)
    run_ms(m, 1)
    assert od.read(POS, 1) == -0x8000_0000 + pulses_after(1000, 60.0) - 1


@pytest.mark.parametrize(("encoder", "bit"), [(1, 0x1000), (2, 0x2000)])
def test_zero_cycle_sets_home_offset_at_the_zero_mark(encoder, bit):
    """§6.12 / §6.27 / §6.30: rising edge of bit 12/13 arms the zero cycle; at the next zero
    mark the position becomes 0x4001.k and 0x6600 bit 12/13 is set."""
    m, od = make()
    od.write(HOME, encoder, -1000)
    spin(m, encoder, 60.0)
    od.write(CMD, 0, bit)
    run_ms(m, 999)  # the first mark is 2047.5 pulses away: ~999.76 ms
    assert od.read(STATUS, 0) == 0
    assert od.read(POS, encoder) == pulses_after(999_000, 60.0)
    run_ms(m, 1)
    assert od.read(STATUS, 0) == bit
    assert od.read(POS, encoder) == -1000
    run_ms(m, 500)
    assert od.read(POS, encoder) == -1000 + pulses_after(1_500_000, 60.0) - 2048
    run_ms(m, 1000)  # holding the bit does not start another cycle
    assert od.read(POS, encoder) == -1000 + pulses_after(2_500_000, 60.0) - 2048
    assert m.snapshot()["encoders"][encoder - 1]["homed"] is True


def test_new_rising_edge_restarts_the_zero_cycle():
    m, od = make()
    spin(m, 1, 60.0)
    od.write(CMD, 0, 0x1000)
    run_ms(m, 1200)
    assert od.read(STATUS, 0) == 0x1000
    od.write(CMD, 0, 0)
    run_ms(m, 1)
    od.write(CMD, 0, 0x1000)
    od.write(HOME, 1, 7)
    run_ms(m, 1)
    assert od.read(STATUS, 0) == 0  # done flag cleared by the new cycle
    assert m.snapshot()["encoders"][0]["homing"] is True
    run_ms(m, 1000)
    assert od.read(STATUS, 0) == 0x1000
    assert od.read(POS, 1) == 7 + pulses_after(2_202_000, 60.0) - 2 * 2048


def test_zero_cycle_backwards():
    """Going backwards the mark is met at the pulse just below it."""
    m, od = make()
    od.write(HOME, 1, 100)
    spin(m, 1, -60.0)
    od.write(CMD, 0, 0x1000)
    run_ms(m, 100)
    assert od.read(STATUS, 0) == 0x1000
    assert od.read(POS, 1) == 100 + pulses_after(100_000, -60.0) - (-1)


@pytest.mark.parametrize(("encoder", "bit", "code"), [(1, 0x1000, 0x14), (2, 0x2000, 0x15)])
def test_zero_cycle_alarm_after_one_and_a_half_turns(encoder, bit, code):
    """§7.6 0x14/0x15: zero mark not found within 1.5 turns (3072 pulses at 2048/rev)."""
    m, od = make()
    m.apply("encoder_fault", {"encoder": encoder, "fault": "no_zero_mark", "active": True})
    assert m.cause_present(code)
    spin(m, encoder, 60.0)
    od.write(CMD, 0, bit)
    run_ms(m, 1490)
    assert m.take_raised_alarms() == []
    run_ms(m, 20)
    assert m.take_raised_alarms() == [code]
    assert od.read(STATUS, 0) == 0
    assert m.snapshot()["encoders"][encoder - 1]["homing"] is False
    run_ms(m, 3000)
    assert m.take_raised_alarms() == []  # the cycle was abandoned: one alarm
    m.apply("encoder_fault", {"encoder": encoder, "fault": "no_zero_mark", "active": False})
    assert not m.cause_present(code)


def test_zero_cycle_limit_is_exact():
    """The 1.5 turns are counted in configured pulses: 3072 passes, 3073 alarms."""
    m, od = make()
    m.apply("encoder_fault", {"encoder": 1, "fault": "no_zero_mark", "active": True})
    spin(m, 1, 60.0)
    od.write(CMD, 0, 0x1000)
    t_us = 0
    while pulses_after(t_us + 100, 60.0) - pulses_after(0, 60.0) <= 3072:
        m.step(100, True)
        t_us += 100
    assert m.take_raised_alarms() == []
    m.step(100, True)
    assert m.take_raised_alarms() == [0x14]


@pytest.mark.parametrize(("encoder", "code"), [(1, 0x10), (2, 0x11)])
def test_count_alarm_when_real_ppr_differs(encoder, code):
    """§6.13: exactly 0x4000.k pulses must be counted between two zero marks."""
    ppr = [2048, 2048]
    ppr[encoder - 1] = 2000
    m, od = make({"encoder_ppr": ppr})
    assert m.cause_present(code)
    spin(m, encoder, 60.0)
    run_ms(m, 1500)  # one mark passed: nothing to compare yet
    assert m.take_raised_alarms() == []
    run_ms(m, 1000)  # second mark: 2000 counted, 2048 expected
    assert m.take_raised_alarms() == [code]
    od.write(PULSES, encoder, 2000)  # set 0x4000 to the real encoder
    assert not m.cause_present(code)
    run_ms(m, 3000)
    assert m.take_raised_alarms() == []


@pytest.mark.parametrize("index", [NO_COUNT_ALARM, DISABLE])
def test_count_alarm_suppressed(index):
    """§6.13 0x4002.k = 1 disables the count alarm; §6.14 0x4003.k = 1 the whole encoder."""
    m, od = make({"encoder_ppr": [1024, 2048]})
    od.write(index, 1, 1)
    assert not m.cause_present(0x10)
    spin(m, 1, 600.0)
    run_ms(m, 1000)
    assert m.take_raised_alarms() == []


def test_pulse_noise_causes_count_alarm():
    m, od = make(seed=7)
    m.apply("encoder_fault", {"encoder": 2, "fault": "pulse_noise", "active": True})
    assert m.cause_present(0x11)
    spin(m, 2, 600.0)  # 10 revolutions per second
    run_ms(m, 2000)
    assert m.take_raised_alarms() == [0x11]
    assert od.read(POS, 2) != 2 * 10 * 2048  # the counter gained or lost pulses
    od.write(NO_COUNT_ALARM, 2, 1)
    run_ms(m, 2000)
    assert m.take_raised_alarms() == []


def test_pulse_noise_is_deterministic():
    def trace(seed):
        m, od = make(seed=seed)
        m.apply("encoder_fault", {"encoder": 1, "fault": "pulse_noise", "active": True})
        spin(m, 1, 300.0)
        run_ms(m, 1000)
        return od.read(POS, 1), m.take_raised_alarms()

    assert trace(3) == trace(3)


@pytest.mark.parametrize(("encoder", "code"), [(1, 0x12), (2, 0x13)])
def test_signal_alarm_and_disable(encoder, code):
    """§7.6 0x12/0x13 while the signal is lost; §6.14 0x4003.k = 1 silences it."""
    m, od = make()
    spin(m, encoder, 60.0)
    run_ms(m, 100)
    m.apply("encoder_fault", {"encoder": encoder, "fault": "signal_lost", "active": True})
    assert m.physical_alarms() == {code} and m.cause_present(code)
    held = od.read(POS, encoder)
    run_ms(m, 500)
    assert od.read(POS, encoder) == held  # no pulses, no counting
    od.write(DISABLE, encoder, 1)
    assert m.physical_alarms() == set() and not m.cause_present(code)
    m.apply("encoder_fault", {"encoder": encoder, "fault": "signal_lost", "active": False})
    run_ms(m, 500)
    assert od.read(POS, encoder) == held  # a disabled encoder does not count
    od.write(CMD, 0, 0x1000 << (encoder - 1))
    run_ms(m, 2000)
    assert od.read(STATUS, 0) == 0 and m.take_raised_alarms() == []  # nor run a zero cycle


def test_lost_signal_restarts_the_mark_to_mark_check():
    """Pulses missed while the signal was lost are not reported as a count alarm."""
    m, _od = make()
    spin(m, 1, 60.0)
    run_ms(m, 1200)
    m.apply("encoder_fault", {"encoder": 1, "fault": "signal_lost", "active": True})
    run_ms(m, 300)
    m.apply("encoder_fault", {"encoder": 1, "fault": "signal_lost", "active": False})
    run_ms(m, 4000)
    assert m.take_raised_alarms() == []


def test_shaft_reversal_across_a_mark_is_not_a_count_alarm():
    m, _od = make()
    spin(m, 1, 60.0)
    run_ms(m, 1100)  # past mark 1
    spin(m, 1, -60.0)
    run_ms(m, 200)  # back across mark 1
    spin(m, 1, 60.0)
    run_ms(m, 3000)  # forward across marks 1, 2, 3
    assert m.take_raised_alarms() == []


def test_fast_shaft_loses_nothing():
    """6000 rpm at 1 ms steps: ~205 pulses and a tenth of a turn per step; 10 s = 1000 turns."""
    stepped, od1 = make()
    spin(stepped, 1, 6000.0)
    run_ms(stepped, 10_000)
    one_go, od2 = make()
    spin(one_go, 1, 6000.0)
    one_go.step(10_000_000, True)
    assert od1.read(POS, 1) == od2.read(POS, 1) == 1000 * 2048
    assert stepped.take_raised_alarms() == [] and one_go.take_raised_alarms() == []


def test_fast_shaft_count_check_still_runs():
    m, od = make()
    od.write(PULSES, 1, 2047)
    spin(m, 1, 6000.0)
    run_ms(m, 30)  # 3 marks
    assert m.take_raised_alarms() == [0x10]


def test_several_marks_in_one_step():
    """At 60000 rpm (one turn per ms) a 10 ms step crosses 10 marks; the zero cycle takes the
    first one and the count check sees every pair."""
    m, od = make()
    od.write(HOME, 1, 5)
    spin(m, 1, 60000.0)
    od.write(CMD, 0, 0x1000)
    m.step(10_000, True)
    assert od.read(STATUS, 0) == 0x1000
    assert od.read(POS, 1) == 5 + pulses_after(10_000, 60000.0) - 2048
    assert m.take_raised_alarms() == []


def test_status_bit_15_follows_module_alarm():
    """§6.27 bit 15: alarm active in the module (the coupler sets in_alarm, §7)."""
    m, od = make()
    m.in_alarm = True
    assert od.read(STATUS, 0) == 0x8000
    m.in_alarm = False
    assert od.read(STATUS, 0) == 0


def test_reset_clears_counters_and_settings():
    m, od = make({"encoder_ppr": [1000, 2048]})
    od.write(PULSES, 1, 1000)
    od.write(CMD, 0, 0x1000)
    spin(m, 1, 60.0)
    run_ms(m, 2000)
    assert od.read(STATUS, 0) == 0x1000
    m.reset()
    assert od.read(POS, 1) == 0 and od.read(STATUS, 0) == 0 and od.read(CMD, 0) == 0
    assert od.read(PULSES, 1) == 2048
    assert m.snapshot()["encoders"][0]["ppr"] == 1000  # the encoder fitted stays
    assert m.snapshot()["encoders"][0]["rpm"] == 60.0
