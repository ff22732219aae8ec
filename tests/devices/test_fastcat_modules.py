"""FastCAT I/O modules: per-module objects (seed 000 §6), PDO entries (§5), process models,
module alarm causes (§7.6), actions and options."""

from __future__ import annotations

import json
import random

import pytest

from devices.device import CommandError
from devices.fastcat.catalog import CATALOG
from devices.fastcat.module_od import OBJECTS, object_index
from devices.fastcat.modules import IoModule
from devices.od import AbortCode, Access, ObjectDictionary, SdoAbort


def make(name, n=1, options=None, seed=0):
    module = IoModule(CATALOG[name], random.Random(seed), options)
    od = ObjectDictionary()
    module.add_objects(od, n)
    return module, od


def run(module, ms, enabled=True, dt_us=1000):
    for _ in range(ms):
        module.step(dt_us, enabled)


def idx(base, n=1):
    return base + 0x10 * (n - 1)


# Which per-module objects each type carries, with their channel count (§6.6-§6.30).
TYPE_OBJECTS = {
    "DB16": {0x2004: 4, 0x6000: 16, 0x7000: 16},
    "DI16": {0x6000: 16},
    "DO82": {0x7000: 8},
    "DO16": {0x7000: 16},
    "AI8D": {0x2104: 1, 0x6400: 8},
    "AI8C": {0x2104: 1, 0x6400: 8},
    "AI8TC": {0x200B: 8, 0x2104: 1, 0x6400: 8},
    "AI8PT100": {0x2104: 1, 0x6400: 8},
    "AI8PT1000": {0x2104: 1, 0x6400: 8},
    "AB4P4": {0x2104: 1, 0x6400: 4, 0x200A: 4, 0x7400: 4},
    "AB4D4": {0x2104: 1, 0x6400: 4, 0x200A: 4, 0x7400: 4},
    "AB4C4": {0x2104: 1, 0x6400: 4, 0x200A: 4, 0x7400: 4},
    "AI4D": {0x2104: 1, 0x6400: 4},
    "AI4C": {0x2104: 1, 0x6400: 4},
    "AO4": {0x200A: 4, 0x7400: 4},
    "AO4H": {0x200A: 4, 0x7400: 4},
    "AI4P": {0x2104: 1, 0x6400: 4},
    "AI8M": {0x2106: 8, 0x4500: 8, 0x6400: 8},
    "AB4M4": {0x2106: 8, 0x4500: 8, 0x6400: 8, 0x200A: 4, 0x7400: 4},
    "AX2": {0x4000: 2, 0x4001: 2, 0x4002: 2, 0x4003: 2, 0x6500: 2, 0x6600: 1, 0x7600: 1},
}


def test_every_type_is_covered():
    assert set(TYPE_OBJECTS) == set(CATALOG)


@pytest.mark.parametrize("n", [1, 2, 16])
@pytest.mark.parametrize("name", list(TYPE_OBJECTS))
def test_objects_at_base_plus_0x10_times_n_minus_1(name, n):
    """§6.6-§6.30: module N's object is base + 0x10 * (N - 1); sub 0 = number of entries."""
    _m, od = make(name, n)
    expected = set()
    for base, count in TYPE_OBJECTS[name].items():
        index = idx(base, n)
        if OBJECTS[base].single:
            expected.add((index, 0))
        else:
            assert od.read(index, 0) == count
            expected |= {(index, sub) for sub in range(count + 1)}
    assert {(e.index, e.sub) for e in od} == expected


def test_index_arithmetic_bounds():
    assert object_index(0x6400, 1) == 0x6400
    assert object_index(0x6400, 16) == 0x64F0
    assert object_index(0x2004, 16) == 0x20F4
    for bad in (0, 17):
        with pytest.raises(ValueError):
            object_index(0x6000, bad)


# (type, index, sub, default) from the §6 tables.
DEFAULTS = [
    ("DB16", 0x2004, 1, 0), ("AO4", 0x200A, 1, 0), ("AI8TC", 0x200B, 8, 0),
    ("AI8D", 0x2104, 0, 4000), ("AB4C4", 0x2104, 0, 4000), ("AI8TC", 0x2104, 0, 100),
    ("AI8PT100", 0x2104, 0, 100), ("AI8PT1000", 0x2104, 0, 100), ("AI8M", 0x2106, 8, 4000),
    ("AX2", 0x4000, 1, 2048), ("AX2", 0x4000, 2, 2048), ("AX2", 0x4001, 1, 0),
    ("AX2", 0x4002, 2, 0), ("AX2", 0x4003, 1, 0), ("AB4M4", 0x4500, 1, 4),
    ("DI16", 0x6000, 1, 0), ("AX2", 0x6500, 1, 0), ("AX2", 0x6600, 0, 0), ("DO16", 0x7000, 1, 0),
    ("AO4H", 0x7400, 4, 0), ("AX2", 0x7600, 0, 0), ("AX2", 0x4000, 0, 2), ("AI8TC", 0x200B, 0, 8),
    ("AI8M", 0x2106, 0, 8), ("AO4", 0x200A, 0, 4), ("DB16", 0x2004, 0, 4),
]


@pytest.mark.parametrize(("name", "index", "sub", "default"), DEFAULTS)
def test_defaults(name, index, sub, default):
    """§6 'Def.Val.' columns (and the sub-0 counts)."""
    _m, od = make(name)
    assert od.read(index, sub) == default


def _entries(name):
    _m, od = make(name, 3)
    return [(name, e.index, e.sub) for e in od]


ALL_ENTRIES = [e for name in CATALOG for e in _entries(name)]


@pytest.mark.parametrize(("name", "index", "sub"), ALL_ENTRIES)
def test_access_rights(name, index, sub):
    """§6 'Attr.': ro objects refuse writes with READ_ONLY; rw ones take their own value."""
    _m, od = make(name, 3)
    entry = od.entry(index, sub)
    base = index - 0x20  # module 3
    spec = OBJECTS[base]
    expected = Access.RO if sub == 0 and not spec.single else spec.access
    assert entry.access is expected
    value = od.read(index, sub)
    if expected is Access.RO:
        with pytest.raises(SdoAbort) as err:
            od.write(index, sub, value)
        assert err.value.code is AbortCode.READ_ONLY
    else:
        od.write(index, sub, value)
        assert od.read(index, sub) == value


def test_startup_objects_printed_ro_are_writable():
    """§3/§4: the master writes 0x2004, 0x200A, 0x200B, 0x2106 in its Startup list although
    §6 prints them ro; nothing else departs from the printed attribute (docs)."""
    changed = {b for b, s in OBJECTS.items() if s.access is not s.seed_access}
    assert changed == {0x2004, 0x200A, 0x200B, 0x2106}
    assert all(OBJECTS[b].access is Access.RW for b in changed)


@pytest.mark.parametrize(("name", "index", "sub", "value", "code"), [
    ("AI8D", 0x2104, 0, 0, AbortCode.VALUE_TOO_LOW),  # §6.9: 1..10000
    ("AI8D", 0x2104, 0, 10001, AbortCode.VALUE_TOO_HIGH),
    ("AI8TC", 0x2104, 0, 0, AbortCode.VALUE_TOO_LOW),
    ("AI8TC", 0x2104, 0, 10001, AbortCode.VALUE_TOO_HIGH),
    ("AI8M", 0x2106, 3, 0, AbortCode.VALUE_TOO_LOW),  # §6.10: 1..10000
    ("AB4M4", 0x2106, 8, 10001, AbortCode.VALUE_TOO_HIGH),
    ("AI8TC", 0x200B, 1, 2, AbortCode.VALUE_TOO_HIGH),  # §6.8: 0 = J, 1 = K
    ("AI8M", 0x4500, 1, 0, AbortCode.VALUE_TOO_LOW),  # §6.15: types 1..5
    ("AI8M", 0x4500, 1, 6, AbortCode.VALUE_TOO_HIGH),
    ("AX2", 0x4000, 1, 0, AbortCode.VALUE_TOO_LOW),  # 0 pulses/rev is no encoder
    ("AO4", 0x7400, 1, 0x8000, AbortCode.VALUE_TOO_HIGH),  # INT (16)
])
def test_value_range_aborts(name, index, sub, value, code):
    _m, od = make(name)
    before = od.read(index, sub)
    with pytest.raises(SdoAbort) as err:
        od.write(index, sub, value)
    assert err.value.code is code
    assert od.read(index, sub) == before


@pytest.mark.parametrize(("index", "value"), [(0x2104, 1), (0x2104, 10000)])
def test_filter_limits_accepted(index, value):
    _m, od = make("AI8D")
    od.write(index, 0, value)
    assert od.read(index, 0) == value


# --- PDO entries (§5) -----------------------------------------------------------------------

def test_sirio_example_third_module_ai8c():
    """§4: the third module, an AI8C, maps 0x6420:1..8 as 16-bit entries in TxPDO 0x1A02."""
    m, _od = make("AI8C", 3)
    assert m.tx_entries(3) == [(0x6420, k, 16) for k in range(1, 9)]
    assert m.rx_entries(3) == []


@pytest.mark.parametrize(("name", "n", "rx", "tx"), [
    ("DB16", 1, [(0x7000, k, 1) for k in range(1, 17)], [(0x6000, k, 1) for k in range(1, 17)]),
    ("DI16", 2, [], [(0x6010, k, 1) for k in range(1, 17)]),
    ("DO82", 16, [(0x70F0, k, 1) for k in range(1, 9)], []),
    ("AB4D4", 4, [(0x7430, k, 16) for k in range(1, 5)], [(0x6430, k, 16) for k in range(1, 5)]),
    ("AO4H", 1, [(0x7400, k, 16) for k in range(1, 5)], []),
    ("AX2", 5, [(0x7640, 0, 16)], [(0x6540, 1, 32), (0x6540, 2, 32), (0x6640, 0, 16)]),
])
def test_pdo_entries(name, n, rx, tx):
    """§5: outputs in RxPDO 0x1600+(N-1), inputs in TxPDO 0x1A00+(N-1). The SDO information
    says which direction each entry maps into (ETG.1000.6 access bits 6 / 7): an AX2's 0x6500
    is rw (§6.26, a preset) yet an input, mapped in the TxPDO."""
    from app.ethercat_wire.coe import RXPDO_MAPPABLE, TXPDO_MAPPABLE, access_word

    m, od = make(name, n)
    assert m.rx_entries(n) == rx
    assert m.tx_entries(n) == tx
    for index, sub, bits in rx + tx:
        entry = od.entry(index, sub)
        assert entry.pdo_mappable and entry.bit_length == bits
    directions = {(i, s): access_word(od.entry(i, s)) & (RXPDO_MAPPABLE | TXPDO_MAPPABLE)
                  for i, s, _bits in rx + tx}
    assert directions == {**{(i, s): RXPDO_MAPPABLE for i, s, _b in rx},
                          **{(i, s): TXPDO_MAPPABLE for i, s, _b in tx}}


# --- digital (§6.6, §6.24, §6.28, §7.6 0x02) -----------------------------------------------

def test_digital_inputs_follow_field():
    m, od = make("DI16", 2)
    m.apply("set_input", {"channel": 16, "value": True})
    m.step(1000, False)  # inputs are read in every state
    assert od.read(0x6010, 16) == 1 and od.read(0x6010, 1) == 0


def test_db16_groups():
    """§6.6: 0x2004:g = 0 -> channels 4g-3..4g are inputs (default), 1 -> outputs."""
    m, od = make("DB16")
    m.apply("set_input", {"channel": 5, "value": True})
    od.write(0x7000, 1, 1)  # channel 1 is in an input group: no output stage active
    run(m, 1)
    assert od.read(0x6000, 5) == 1
    assert m.snapshot()["do"][0] is False
    od.write(0x2004, 2, 1)  # channels 5..8 become outputs
    run(m, 1)
    assert od.read(0x6000, 5) == 0  # an output group reads back its own (off) state
    od.write(0x7000, 5, 1)
    run(m, 1)
    assert od.read(0x6000, 5) == 1
    assert m.snapshot()["do"][4] is True
    assert m.snapshot()["groups"] == ["inputs", "outputs", "inputs", "inputs"]


@pytest.mark.parametrize("name", ["DO82", "DO16"])
def test_outputs_only_when_enabled(name):
    """Outputs follow 0x7000 in OP without alarm; otherwise the safe state is all off."""
    m, od = make(name)
    od.write(0x7000, 3, 1)
    run(m, 1, enabled=True)
    assert m.snapshot()["do"][2] is True
    run(m, 1, enabled=False)
    assert m.snapshot()["do"] == [False] * CATALOG[name].do
    assert od.read(0x7000, 3) == 1  # the master's image is kept


def test_output_short_is_a_readback_fault():
    """§7.6 0x02 CO_E_IOFAULT: an output driven on reads back off."""
    m, od = make("DO82")
    m.apply("output_short", {"channel": 2, "active": True})
    run(m, 1)
    assert m.physical_alarms() == set()  # output off: no current, no fault
    od.write(0x7000, 2, 1)
    run(m, 1, enabled=False)
    assert m.physical_alarms() == set()  # outputs disabled: not driven
    run(m, 1)
    assert m.physical_alarms() == {0x02} and m.cause_present(0x02)
    assert m.snapshot()["do"][1] is False
    m.apply("output_short", {"channel": 2, "active": False})
    run(m, 1)
    assert m.physical_alarms() == set() and not m.cause_present(0x02)
    assert m.snapshot()["do"][1] is True


# --- analog inputs (§6.9, §6.10, §6.15, §6.25) ---------------------------------------------

@pytest.mark.parametrize(("name", "value", "raw"), [
    ("AI8D", 10.0, 2047), ("AI8D", -10.0, -2047), ("AI8D", 5.0, 1024), ("AI8D", 12.0, 2047),
    ("AI4D", -2.5, -512), ("AI8C", 20.0, 4096), ("AI8C", 4.0, 819), ("AI8C", 24.0, 4096),
    ("AB4C4", 10.0, 2048), ("AI4P", 50.0, 2048), ("AB4P4", 100.0, 4096),
    ("AI8PT100", 25.3, 253), ("AI8PT1000", -12.5, -125), ("AI8TC", 300.0, 3000),
])
def test_input_scaling(name, value, raw):
    """Raw codes of 0x6400: ±10 V -> ±2047, 0..20 mA / pot -> 0..4096, °C in tenths."""
    m, od = make(name)
    od.write(0x2104, 0, 10000)  # no filter
    m.apply("set_analog", {"channel": 1, "value": value})
    run(m, 1)
    assert od.read(0x6400, 1) == raw


def test_filter_10000_is_immediate_and_smaller_is_slower():
    """§6.9: 10000 = no filter, 1 = most filtering; y += (x - y) * f / 10000 per ms."""
    traces = {}
    for f in (10000, 4000, 100, 1):
        m, od = make("AI8D")
        od.write(0x2104, 0, f)
        m.apply("set_analog", {"channel": 1, "value": 10.0})
        trace = []
        for _ in range(50):
            run(m, 1)
            trace.append(od.read(0x6400, 1))
        traces[f] = trace
        assert trace == sorted(trace)  # monotone towards the target
        for k in (1, 10, 50):
            assert trace[k - 1] == round(2047 * (1 - (1 - f / 10000) ** k))
    assert traces[10000][0] == 2047
    for k in range(50):
        assert traces[4000][k] >= traces[100][k] >= traces[1][k]
    assert traces[4000][-1] == 2047 and traces[100][-1] < 2047


def test_filter_does_not_depend_on_step_size():
    """20 ms of simulated time give the same reading however the runtime slices them."""
    results = set()
    for dt_us, steps in ((1000, 20), (250, 80), (20000, 1), (4000, 5), (700, 28)):
        m, od = make("AI8TC")  # default filter 100 (§6.9)
        m.apply("set_analog", {"channel": 2, "value": 400.0})
        for _ in range(steps):
            m.step(dt_us, True)
        if dt_us == 700:
            m.step(20000 - 700 * 28, True)
        results.add(od.read(0x6400, 2))
    assert len(results) == 1


def test_thermocouple_j_vs_k():
    """§6.8: the module linearises with the configured couple; a K couple read as J is low."""
    m, od = make("AI8TC", options={"thermocouple": ["K"] + ["J"] * 7, "cold_junction_c": 25.0})
    od.write(0x2104, 0, 10000)
    for ch in (1, 2):
        m.apply("set_analog", {"channel": ch, "value": 200.0})
    run(m, 1)
    assert od.read(0x6400, 2) == 2000  # J wired, J configured (default 0)
    assert od.read(0x6400, 1) == 1685  # K wired, read as J: 25 + 175 * 41/50 = 168.5 °C
    od.write(0x200B, 1, 1)  # configure channel 1 as K
    run(m, 1)
    assert od.read(0x6400, 1) == 2000
    od.write(0x200B, 2, 1)  # a J couple read as K reads high: 25 + 175 * 50/41
    run(m, 1)
    assert od.read(0x6400, 2) == round(10 * (25 + 175 * 50 / 41))


@pytest.mark.parametrize(("ai_type", "value", "raw"), [
    (1, 50.0, 2048),  # potentiometer 0:4096
    (2, 20.0, 4096),  # current 0:20 mA 0:4096
    (3, 5.0, 2048),  # differential 0:10 V 0:4096
    (3, -1.0, 0),
    (4, -10.0, -2047),  # differential -10:10 V -2047:2047 (default)
    (5, 21.7, 217),  # PT100, tenths of °C
])
@pytest.mark.parametrize("name", ["AI8M", "AB4M4"])
def test_configurable_input_types(name, ai_type, value, raw):
    """§6.15: 0x4500 per-channel type; §6.10: 0x2106 per-channel filter."""
    m, od = make(name, 2)
    od.write(0x4510, 4, ai_type)
    od.write(0x2116, 4, 10000)
    m.apply("set_analog", {"channel": 4, "value": value})
    run(m, 1)
    assert od.read(0x6410, 4) == raw
    assert m.snapshot()["ai_type"][3] == ai_type


def test_configurable_filter_is_per_channel():
    m, od = make("AI8M")
    od.write(0x2106, 1, 10000)
    for ch in (1, 2):
        m.apply("set_analog", {"channel": ch, "value": 10.0})
    run(m, 1)
    assert od.read(0x6400, 1) == 2047
    assert od.read(0x6400, 2) == round(2047 * 0.4)  # default 4000 after 1 ms


def test_set_analog_checks_the_channel_range():
    m, _od = make("AI8C")
    with pytest.raises(CommandError, match="mA"):
        m.apply("set_analog", {"channel": 1, "value": -1.0})
    with pytest.raises(CommandError, match=r"1\.\.8"):
        m.apply("set_analog", {"channel": 9, "value": 1.0})


# --- analog outputs (§6.7, §6.29) ----------------------------------------------------------

def test_ao_ramp_bits_per_ms():
    """§6.7: the output moves 0x200A bits per ms towards the 0x7400 target; 0 = step."""
    m, od = make("AO4")
    od.write(0x200A, 1, 10)
    od.write(0x7400, 1, 1000)
    od.write(0x7400, 2, -700)  # ramp 0 on channel 2
    run(m, 1)
    assert m.snapshot()["ao"][:2] == [10, -700]
    run(m, 49)
    assert m.snapshot()["ao"][0] == 500
    run(m, 60)
    assert m.snapshot()["ao"][0] == 1000
    od.write(0x7400, 1, 995)
    run(m, 1)
    assert m.snapshot()["ao"][0] == 995  # last step shorter than the ramp


def test_ao_ramp_counts_whole_milliseconds():
    m, od = make("AB4D4")
    od.write(0x200A, 3, 4)
    od.write(0x7400, 3, 100)
    run(m, 10, dt_us=250)  # 2.5 ms
    assert m.snapshot()["ao"][2] == 8


@pytest.mark.parametrize(("name", "target", "code"), [
    ("AO4", 5000, 2047), ("AO4", -5000, -2047), ("AO4H", 30000, 30000), ("AO4H", -32768, -32767),
])
def test_ao_resolution(name, target, code):
    """§2: AO4 12 bit (±2047), AO4H 16 bit (±32767); the DAC saturates."""
    m, od = make(name)
    od.write(0x7400, 1, target)
    run(m, 1)
    assert m.snapshot()["ao"][0] == code
    assert abs(m.snapshot()["ao_volts"][0]) <= 10.0


def test_ao_safe_state_and_overload():
    """Not enabled -> 0 at once; overload -> protection (§7.6 0x04), outputs 0."""
    m, od = make("AB4P4")
    od.write(0x7400, 1, 1500)
    run(m, 1)
    assert m.snapshot()["ao"][0] == 1500
    run(m, 1, enabled=False)
    assert m.snapshot()["ao"][0] == 0
    run(m, 1)
    m.apply("ao_overload", {"active": True})
    run(m, 1)
    assert m.snapshot()["ao"][0] == 0
    assert m.physical_alarms() == {0x04} and m.cause_present(0x04)
    m.apply("ao_overload", {"active": False})
    run(m, 1)
    assert m.physical_alarms() == set() and m.snapshot()["ao"][0] == 1500


# --- module alarm causes (§7.6) --------------------------------------------------------------

@pytest.mark.parametrize("name", ["AB4P4", "AI4P"])
def test_pot_supply_short(name):
    """§7.6 0x03 CO_E_ALARM_10V; the wipers read 0 without their reference supply."""
    m, od = make(name, options={"analog": [60.0] * 4})
    od.write(0x2104, 0, 10000)
    run(m, 1)
    assert od.read(0x6400, 1) == round(0.6 * 4096)
    m.apply("pot_supply_short", {"active": True})
    run(m, 1)
    assert m.physical_alarms() == {0x03} and od.read(0x6400, 1) == 0
    m.apply("pot_supply_short", {"active": False})
    assert not m.cause_present(0x03)


def test_pot_supply_short_on_configurable_needs_a_pot_channel():
    m, od = make("AB4M4")
    m.apply("pot_supply_short", {"active": True})
    assert m.physical_alarms() == set()
    od.write(0x4500, 3, 1)
    assert m.physical_alarms() == {0x03}


def test_not_calibrated():
    """§7.2 example / §7.6 0x0B CO_E_TARATURA."""
    m, _od = make("AI8D", options={"calibrated": False})
    assert m.physical_alarms() == {0x0B} and m.cause_present(0x0B)
    m.apply("calibrated", {"value": True})
    assert m.physical_alarms() == set() and not m.cause_present(0x0B)


def test_module_failure_stops_answering():
    m, _od = make("DI16")
    assert m.responds()
    m.apply("module_failure", {"active": True})
    assert not m.responds()
    m.failed = False
    m.powered = False
    assert not m.responds()
    m.powered = True
    m.plugged = False
    assert not m.responds()


# --- actions and options ----------------------------------------------------------------------

@pytest.mark.parametrize(("name", "action", "args"), [
    ("DI16", "ao_overload", {"active": True}),
    ("DO16", "set_input", {"channel": 1, "value": True}),
    ("AI8D", "set_shaft_speed", {"encoder": 1, "rpm": 10.0}),
    ("AI8D", "pot_supply_short", {"active": True}),
    ("AX2", "calibrated", {"value": False}),
    ("AI8PT100", "wire_thermocouple", {"channel": 1, "type": "K"}),
    ("DI16", "output_short", {"channel": 1, "active": True}),
])
def test_action_that_does_not_fit_the_type(name, action, args):
    m, _od = make(name)
    assert action not in m.available_actions()
    with pytest.raises(CommandError, match=name):
        m.apply(action, args)


def test_unknown_action_and_bad_arguments():
    m, _od = make("AX2")
    with pytest.raises(CommandError, match="set_shaft_speed"):
        m.apply("spin", {})
    with pytest.raises(CommandError, match="fault"):
        m.apply("encoder_fault", {"encoder": 1, "fault": "smoke", "active": True})
    with pytest.raises(CommandError):
        m.apply("set_shaft_speed", {"encoder": 3, "rpm": 1.0})


def test_every_action_has_a_handler():
    for name, action in IoModule.ACTIONS.items():
        assert callable(getattr(IoModule, f"cmd_{name}"))
        assert action.module == "required"  # exposed as fastcat/N targets


@pytest.mark.parametrize(("name", "options", "match"), [
    ("DI16", {"colour": "red"}, "unknown module option 'colour'"),
    ("DI16", {"encoder_ppr": [1024, 1024]}, "encoder inputs"),
    ("DI16", {"inputs": [True] * 15}, "list of 16"),
    ("AI8TC", {"thermocouple": "T"}, "thermocouple"),
    ("AI8D", {"calibrated": "no"}, "true/false"),
    ("AI8D", {"analog": [50.0] * 8}, r"-12\.\.12"),
    ("AX2", {"encoder_ppr": [0, 2048]}, "ppr"),
    ("AX2", {"shaft_rpm": "fast"}, "rpm"),
])
def test_bad_options(name, options, match):
    with pytest.raises(ValueError, match=match):
        IoModule(CATALOG[name], random.Random(0), options)


def test_options_set_the_field():
    m, od = make("DB16", options={"inputs": [True, False] * 8})
    m.step(1000, True)
    assert [od.read(0x6000, k) for k in (1, 2, 3)] == [1, 0, 1]
    m, od = make("AI4C", options={"analog": [4.0, 8.0, 12.0, 20.0]})
    assert [od.read(0x6400, k) for k in range(1, 5)] == [819, 1638, 2458, 4096]  # settled


def test_reset_restores_defaults_and_switches_outputs_off():
    """CNF / power-up (§2): settings back to §6 defaults, outputs off; the field stays."""
    m, od = make("AB4M4", options={"analog": [1.0] * 8})
    od.write(0x4500, 1, 5)
    od.write(0x2106, 1, 7)
    od.write(0x200A, 2, 3)
    od.write(0x7400, 1, 900)
    run(m, 5)
    m.reset()
    assert od.read(0x4500, 1) == 4 and od.read(0x2106, 1) == 4000 and od.read(0x200A, 2) == 0
    assert od.read(0x7400, 1) == 0 and m.snapshot()["ao"] == [0] * 4
    assert m.snapshot()["field"]["analog"] == [1.0] * 8


@pytest.mark.parametrize("name", list(CATALOG))
def test_snapshot_is_plain_data(name):
    m, _od = make(name)
    run(m, 3)
    snap = m.snapshot()
    assert json.loads(json.dumps(snap)) == snap
    assert snap["type"] == name
    assert ("encoders" in snap) == (name == "AX2")
    assert ("ai" in snap) == (CATALOG[name].ai > 0)
    assert ("ao" in snap) == (CATALOG[name].ao > 0)
