"""Random command sequences: the drive refuses bad input with AccessError / CommandError /
SdoAbort only, and its two views keep agreeing whatever happens."""

from __future__ import annotations

import contextlib
import json

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from servo_helpers import make_sim

from devices.device import CommandError
from devices.od import SdoAbort
from devices.servo import ds402
from devices.servo.ds402 import State
from devices.servo.io import INPUT_NAMES

VALUE = st.one_of(st.integers(-(1 << 33), 1 << 33), st.sampled_from(
    [0, 1, 3, 6, 7, 8, 0x0F, 0x1F, 0x23, 0x43, 0x80, -1, -50, 0xFFFF_FFFF]))
STEP = st.one_of(
    st.tuples(st.just("reg"), st.integers(-2, 136), VALUE),
    st.tuples(st.just("par"), st.sampled_from([0, 1, 3, 5, 20, 22, 35, 81, 99, 0x3802, 0x8000]),
              VALUE),
    st.tuples(st.just("cw"), st.sampled_from([0, 2, 6, 7, 0x0F, 0x1F, 0x5F, 0x80, 0x10F]),
              st.just(0)),
    st.tuples(st.just("od"), st.sampled_from([(0x6060, 0), (0x607A, 0), (0x60FF, 0),
                                              (0x2000, 1), (0x2006, 1), (0x1010, 1)]), VALUE),
    st.tuples(st.just("input"), st.sampled_from(INPUT_NAMES), st.booleans()),
    st.tuples(st.just("run"), st.integers(1, 400), st.just(0)),
    st.tuples(st.just("alarm"), st.sampled_from([1, 5, 16, 17, 34]), st.booleans()),
    st.tuples(st.just("jam"), st.booleans(), st.just(0)),
    st.tuples(st.just("power"), st.booleans(), st.just(0)),
)


def _apply(sim, kind, a, b) -> None:
    d = sim.drive
    if kind == "reg":
        d.write_register(a, b)
    elif kind == "par":
        d.write_parameter(a, b)
    elif kind == "cw":
        d.write_controlword(a)
    elif kind == "od":
        d.od.write(a[0], a[1], b)
    elif kind == "input":
        d.apply("set_input", {"name": a, "value": b})
    elif kind == "run":
        sim.run(a)
    elif kind == "alarm":
        d.apply("inject_alarm" if b else "clear_alarm", {"code": a})
    elif kind == "jam":
        d.apply("jam_load", {"active": a})
    elif kind == "power":
        d.apply("power", {"on": a})


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(STEP, min_size=1, max_size=25))
def test_random_sequences_keep_the_views_consistent(steps) -> None:
    sim = make_sim()
    for kind, a, b in steps:
        with contextlib.suppress(CommandError, SdoAbort):  # refusals are allowed, nothing else
            _apply(sim, kind, a, b)
        d = sim.drive
        json.dumps(d.snapshot())
        if not d.powered:
            continue
        sw, r05 = d.statusword, d.read_register(5)
        assert ds402.state_of(sw) is d.state
        assert bool(r05 & 0x01) == d.state.in_torque
        assert bool(r05 & 0x08) == (d.state in (State.FAULT, State.FAULT_REACTION_ACTIVE))
        assert d.read_register(46) == d.alarms.active
        assert (d.read_register(46) != 0) == (d.state in (State.FAULT,
                                                          State.FAULT_REACTION_ACTIVE))
        assert -0x8000_0000 <= d.read_register(6) <= 0x7FFF_FFFF
