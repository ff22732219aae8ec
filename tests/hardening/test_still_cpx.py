"""Skipping still CPX-E-EC steps changes nothing (docs/cpx-e-ec.md "Still steps").

The CPX-E-EC skips a step that repeats a full step which left its state exactly as it found it
(devices/cpx/stillness.py). Exact or wrong: the same runs with ``SKIP_STILL`` = False on the
CPX-E-EC (every other device as it is, in both runs) must give the same events, in the same
order at the same microsecond, and the same snapshots.

- the example scenarios that work the CPX-E-EC (seed 002 §2.5 short circuit, the pulled cable
  that cuts it off the master) and one that works every part of it (inputs, analog values,
  outputs, faults, supplies, switches, restart);
- a seeded random differential on two default rigs: commands to the CPX-E-EC and its modules,
  named faults (seed 002 Tab. 12, 17, 21), object writes and reads (Tab. 27), master cable /
  power / DC faults, with idle stretches of up to 900 steps; every step's events compared,
  and after each stretch every snapshot and the CPX-E-EC's full ``state_key``;
- the CPX-E-EC alone (no master: traffic, "no master" and the watchdog run out on the clock)
  at step lengths other than 1 ms, with a counting 1CI module.

Each checks that steps were skipped, so skipping switched off by mistake fails it.
"""

from __future__ import annotations

import dataclasses
import json
import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from still_runs import checkpoint_run, scenario_rig

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario, parse_scenario
from devices.cpx.device import CpxEEc
from devices.cpx.faults import FAULTS
from devices.cpx.stillness import VALUES, state_key
from devices.cpx.switches import DIL_MODES
from devices.device import CommandError
from devices.ethercat import AlState
from devices.od import SdoAbort
from devices.stillness import slot_names

ROOT = Path(__file__).resolve().parents[2]
CPX_SCENARIOS = ("cpx_short_circuit", "cable_pulled")

WORK_THE_CPX = """
[scenario]
name = "CPX-E-EC worked: field, outputs, faults, supplies"
duration_s = 8

[[step]]
at = 2.0
target = "cpx/1"
action = "set_input"
channel = 3
on = true

[[step]]
at = 2.1
target = "cpx"
action = "write_object"
index = 0x7002
sub = 1
value = 1

[[step]]
at = 2.2
target = "cpx/3"
action = "set_analog"
channel = 0
value = 4.5

[[step]]
at = 2.3
target = "cpx"
action = "write_object"
index = 0x2003
sub = 2
value = 6

[[step]]
at = 2.4
target = "cpx/3"
action = "set_analog"
channel = 1
value = 1.0

[[step]]
at = 2.5
checkpoint = "worked"

[[step]]
at = 2.55
target = "cpx/3"
action = "set_analog"
channel = 1
value = 12.0

[[step]]
at = 2.6
target = "cpx/1"
action = "force"
channel = 2
value = 1

[[step]]
at = 3.0
target = "cpx"
action = "supply"
out = 12.0

[[step]]
at = 3.5
target = "cpx"
action = "supply"
out = 24.0

[[step]]
at = 3.6
target = "cpx"
action = "inject_fault"
fault = "watchdog"

[[step]]
at = 4.0
checkpoint = "watchdog"

[[step]]
at = 4.2
target = "cpx"
action = "clear_fault"
fault = "watchdog"

[[step]]
at = 4.5
target = "cpx"
action = "power"
on = false

[[step]]
at = 4.51
target = "cpx"
action = "power"
on = true

[[step]]
at = 5.0
target = "cpx"
action = "power"
on = false

[[step]]
at = 5.5
target = "cpx"
action = "power"
on = true

[[step]]
at = 6.0
checkpoint = "back"
"""


def cpx_devices(rig: Rig) -> list[CpxEEc]:
    return [d for d in rig.devices.values() if isinstance(d, CpxEEc)]


def no_skipping(rig: Rig) -> Rig:
    for device in cpx_devices(rig):
        device.SKIP_STILL = False
    return rig


def skipped(rig: Rig) -> int:
    return sum(d._still.skipped for d in cpx_devices(rig))


def scenario_run(scenario: Any, skip: bool) -> tuple[list[str], dict[str, Any], int]:
    rig = scenario_rig(scenario)
    if not skip:
        no_skipping(rig)
    return (*checkpoint_run(scenario, rig), skipped(rig))


def assert_same_runs(scenario: Any) -> tuple[list[str], dict[str, Any]]:
    events, snapshots, count = scenario_run(scenario, True)
    plain_events, plain_snapshots, plain_count = scenario_run(scenario, False)
    assert events == plain_events
    assert snapshots == plain_snapshots
    assert plain_count == 0 and count > 1000  # the CPX-E-EC did skip, and only with skipping
    return events, snapshots


@pytest.mark.parametrize("name", CPX_SCENARIOS)
def test_cpx_scenarios_are_the_same_without_skipping(name: str) -> None:
    """Seed 002 §2.5 (short circuit, 0x10F3, emergency 0x2320) and the pulled cable."""
    assert_same_runs(load_scenario(ROOT / "static" / "scenarios" / f"{name}.toml"))


def test_worked_cpx_scenario_is_the_same_without_skipping() -> None:
    """Seed 002 Tab. 11-13 (ESM and LEDs), Tab. 21 (diagnosis), Tab. 29 (bridging)."""
    events, snapshots = assert_same_runs(parse_scenario(WORK_THE_CPX, "<worked CPX-E-EC>"))
    kinds = {json.loads(line)["event"] for line in events if '"cpx"' in line}
    assert {"state", "alarm", "led", "emergency"} <= kinds  # the run did work the CPX-E-EC
    errors = snapshots["worked"]["devices"]["cpx"]["diagnosis"]["errors"]
    assert {"cause": "wire_break", "module": 3, "channel": 1} in [
        {k: e[k] for k in ("cause", "module", "channel")} for e in errors]  # 4-20 mA at 1 mA


# ---- random differential -------------------------------------------------------------------
Op = tuple[str, str, dict[str, Any]]
OBJECT_WRITES = (  # (index, sub, values) of the default rig's CPX-E-EC (Tab. 27)
    (0x7002, 1, (0, 1)), (0x7002, 4, (0, 1)), (0x7004, 1, (0, 8000, 32767)),
    (0x7000, 1, (0, 0x8000 | 1936, 0x8000 | 2008 + 8)), (0x2003, 1, (1, 2, 5, 6)),
    (0x2004, 2, (1, 5, 6)), (0x2102, 1, (0, 1)), (0x2400, 2, (0, 1)), (0x2400, 3, (0, 1)),
    (0x2400, 4, (0, 1)), (0x2400, 7, (0, 1, 2)), (0x2401, 0, (0, 1)), (0x10F3, 5, (0, 1, 3)),
    (0x10F3, 3, (0, 6, 7)), (0xF030, 0, (0, 5)),
)


def random_fault(rng: random.Random, module: int) -> tuple[str, dict[str, Any]]:
    """A fault of the catalogue with the target and arguments it takes (inject / clear)."""
    fault = rng.choice(tuple(FAULTS))
    fault_args: dict[str, Any] = {"fault": fault}
    target_kind = FAULTS[fault].target.name
    fault_target = "cpx"
    if target_kind in ("MODULE", "CHANNEL"):
        fault_target = f"cpx/{rng.choice((2, 3, 4)) if fault != 'module_failure' else module}"
    if target_kind == "CHANNEL" or (fault == "short_circuit" and rng.random() < 0.7):
        fault_args["channel"] = rng.randint(0, 3)
    if target_kind == "SYNC_MANAGER":
        fault_args["sm"] = rng.randint(0, 3)
    return fault_target, fault_args


def random_op(rng: random.Random) -> Op:
    module = rng.randint(1, 4)
    fault_target, fault_args = random_fault(rng, module)
    index, sub, values = rng.choice(OBJECT_WRITES)
    choices: list[Callable[[], Op]] = [
        lambda: ("cpx/1", "set_input", {"channel": rng.randint(0, 15), "on": rng.random() < 0.5}),
        lambda: ("cpx/3", "set_analog", {"channel": rng.randint(0, 3),
                                         "value": rng.choice((0.0, 1.0, 4.0, 12.5, 25.0))}),
        lambda: (f"cpx/{module}", "short_circuit", {"on": rng.random() < 0.6,
                                                    "channel": rng.randint(0, 3)}),
        lambda: ("cpx/3", "short_circuit", {"on": rng.random() < 0.6}),
        lambda: (f"cpx/{module}", "wire_break", {"channel": rng.randint(0, 3),
                                                 "on": rng.random() < 0.6}),
        lambda: (f"cpx/{module}", "force", {"channel": rng.randint(0, 7),
                                            **({"value": rng.randint(0, 1)}
                                               if rng.random() < 0.6 else {})}),
        lambda: (fault_target, "inject_fault", fault_args),
        lambda: (fault_target, "clear_fault", fault_args),
        lambda: ("cpx", "write_object", {"index": index, "sub": sub,
                                         "value": rng.choice(values)}),
        lambda: ("cpx", "read_object", {"index": 0x10F3, "sub": rng.choice((2, 4, 6, 7))}),
        lambda: ("cpx", "power", {"on": rng.random() < 0.7}),
        lambda: ("cpx", "supply", {"el_sen": rng.choice((24.0, 24.0, 17.0, 5.0)),
                                   "out": rng.choice((24.0, 24.0, 12.0, 0.0))}),
        lambda: ("cpx", "cable", {"port": rng.choice(("in", "out")),
                                  "connected": rng.random() < 0.6}),
        lambda: ("cpx", "set_dil", {"dil1": rng.random() < 0.3, "dil2": rng.random() < 0.7}),
        lambda: ("cpx", "restart", {}),
        lambda: ("master", "pull_cable", {"cable": rng.choice((2, 3))}),
        lambda: ("master", "plug_cable", {"cable": rng.choice((2, 3))}),
        lambda: ("master", "power_slave", {"position": 2, "on": rng.random() < 0.7}),
        lambda: ("master", "dc_fault", {"kind": rng.choice(("jitter", "sync0_lost", "drift"))}),
        lambda: ("master", "clear_dc_fault", {}),
        lambda: ("master", "resync", {}),
        # the wire's face (app/ethercat_wire/faces): straight into the model, not apply()
        lambda: ("cpx", "face_write", {"index": index, "sub": sub,
                                       "value": rng.choice(values)}),
        lambda: ("cpx", "face_write", {"index": 0x7002, "sub": rng.randint(1, 8),
                                       "value": int(rng.random() < 0.7)}),
        lambda: ("cpx", "face_write", {"index": 0x7004, "sub": rng.randint(1, 4),
                                       "value": rng.choice((0, 5000, 20000))}),
        lambda: ("cpx", "face_read", {"index": 0x10F3, "sub": rng.choice((2, 6, 7))}),
        lambda: ("cpx", "face_unknown", {"value": rng.choice((0x05, 0x0F)),
                                         "ack": rng.random() < 0.5}),
    ]
    return rng.choice(choices)()


def _wire(model: CpxEEc, action: str, args: dict[str, Any]) -> Any:
    """What app/ethercat_wire/faces/base.py and cpx.py call on the model."""
    if action == "face_write":
        return model.cmd_write_object(args["index"], args["sub"], args["value"])
    if action == "face_read":
        return model.cmd_read_object(args["index"], args["sub"])
    if model.reachable():  # Face.request_unknown_state: the ESM holder answers
        model.esm.request_unknown(args["value"], args["ack"], model.now_us)
    return None


# Back to a line that can reach OP: every few operations, so that most run on a CPX-E-EC in
# OP with the master's frames passing (where skipping saves most and has most to miss).
HEAL: tuple[Op, ...] = (
    ("cpx", "set_dil", {"dil1": True, "dil2": False}),  # default.toml's, before a power-up
    ("master", "power_slave", {"position": 2, "on": True}),
    ("master", "plug_cable", {"cable": 2}), ("master", "plug_cable", {"cable": 3}),
    ("cpx", "power", {"on": True}), ("cpx", "supply", {"el_sen": 24.0, "out": 24.0}),
    ("cpx", "cable", {"port": "in", "connected": True}),
    ("cpx", "clear_fault", {"fault": "ac_failure"}), ("cpx", "clear_fault", {"fault": "watchdog"}),
    ("master", "clear_dc_fault", {}),
)
RIG_MODE = DIL_MODES[(True, False)]  # the I/O diagnostic interface the ENI's 0xF030 expects
# Injected faults that refuse a transition on the way to OP for as long as they are held
# (docs/cpx-e-ec.md "Codes"): SM settings INIT -> PREOP (AL 0x0016 / 0x001D / 0x001E), the
# ident check PREOP -> SAFEOP (0x0070), a failed boot (Tab. 12 flickering: no application).
KEEP_OUT_OF_OP = ("sm_invalid_address", "sm_invalid_size", "sm_invalid_settings",
                  "module_ident_mismatch", "booting_error")


def heal(rig: Rig) -> list[Op]:
    """HEAL, after taking away what HEAL's fixed list cannot: the injected faults that keep
    the CPX-E-EC out of OP, and a bus node that runs another DIL mode than the rig file's or
    failed its boot (then a restart, as a field engineer would restart it).

    A random clear_fault rarely names the exact fault (sync manager, module) that is held,
    so such a fault stayed for the rest of the run. A DIL change takes effect at the next
    restart or power-up (seed 002 §2.1.7) and changes the bus module's ident (docs/cpx-e-ec.md
    choice 16): against the 0xF030 the master writes, the CPX-E-EC then stays in PREOP with AL
    0x0070, and with DIL on / on (the bootloader) in INIT with 0x0014, for as long as it runs
    that mode. Seed 22 found the CPX-E-EC in OP at 16 of its 300 operations that way."""
    cpx = cpx_devices(rig)[0]
    ops: list[Op] = []
    for held in cpx.snapshot()["injected"]:
        if held["fault"] in KEEP_OUT_OF_OP:
            args = {k: v for k, v in held.items() if k != "module" and v is not None}
            target = "cpx" if held["module"] is None else f"cpx/{held['module']}"
            ops.append((target, "clear_fault", args))
    ops += HEAL
    if cpx.powered and (cpx.switches.active_mode is not RIG_MODE or cpx.boot_failed):
        ops.append(("cpx", "restart", {}))
    return ops


def outcome(rig: Rig, op: Op) -> str:
    try:
        if op[1].startswith("face_"):
            result = _wire(rig.devices["cpx"], op[1], op[2])  # type: ignore[arg-type]
            return repr(result)
        return repr(rig.apply(*op))
    except (CommandError, SdoAbort) as exc:
        return f"refused: {exc}"


def full_state(rig: Rig) -> tuple[Any, ...]:
    return rig.snapshot(), tuple(state_key(d) for d in cpx_devices(rig))


@pytest.mark.parametrize("seed", [21, pytest.param(22, marks=pytest.mark.full)])
def test_random_differential_on_the_default_rig(seed: int, full: bool) -> None:
    rng = random.Random(seed)
    spec = load_rig_spec(DEFAULT_RIG)
    skipping, plain = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    for _ in range(3000):  # power-up, master to OP
        assert skipping.step() == plain.step()
    in_op = 0
    for i in range(400 if full else 48):
        ops = [random_op(rng)] if i % 4 else heal(skipping)
        in_op += bool(i % 4) and cpx_devices(skipping)[0].esm.state is AlState.OP
        for op in ops:
            assert outcome(skipping, op) == outcome(plain, op), op
            assert skipping.take_events() == plain.take_events(), op
        for _ in range(rng.choice((2500, 4000) if i % 4 == 0 else (1, 2, 5, 30, 200, 900))):
            assert skipping.step() == plain.step(), op
        assert full_state(skipping) == full_state(plain), op
    assert skipped(plain) == 0
    assert skipped(skipping) > 2000  # the CPX-E-EC did settle and skip
    assert in_op >= (80 if full else 20)  # operations did find the CPX-E-EC in OP


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_cpx_alone_at_other_step_lengths(seed: int, full: bool) -> None:
    """No master: LA IN / LA OUT, Error (no master) and the SM watchdog follow the clock."""
    rng = random.Random(seed)
    models = [CpxEEc("cpx", random.Random(5),
                     modules=["CPX-E-16DI", "CPX-E-8DO", "CPX-E-4AI-U-I", "CPX-E-4AO-U-I",
                              "CPX-E-1CI"]) for _ in range(2)]
    models[1].SKIP_STILL = False
    rigs = [Rig("cpx", {"cpx": m}) for m in models]
    t_us = 0
    for _ in range(120 if full else 30):
        if rng.random() < 0.15:
            op: Op = ("cpx/5", "set_count_rate", {"hz": rng.choice((0.0, 0.0, 150.0, -20.0))})
        elif rng.random() < 0.2:
            op = ("cpx", "exchange_frame", {})
        else:
            op = random_op(rng)
            if op[0] == "master":
                continue
        if op[1] == "exchange_frame":  # a master's frame, without a master
            for model in models:
                model.exchange_frame(t_us)
        else:
            assert outcome(rigs[0], op) == outcome(rigs[1], op), op
        dt = rng.choice((250, 1000, 2000, 3500))
        for _ in range(rng.choice((1, 10, 60, 300))):
            t_us += dt
            for model in models:
                model.step(t_us)
            assert models[0].drain_events() == models[1].drain_events(), op
        assert state_key(models[0]) == state_key(models[1]), op
        assert models[0].snapshot() == models[1].snapshot(), op
    assert models[1]._still.skipped == 0 and models[0]._still.skipped > 100


def test_values_taken_as_they_are_are_deeply_immutable() -> None:
    """stillness.VALUES are compared by ==, not copied: frozen dataclasses whose instances
    hash (so no list, dict or set inside), as every instance in a worked model does."""
    # the I/O diagnostic interface (DIL 1 on): the errors are stored as DiagMessages (§2.5)
    model = CpxEEc("cpx", random.Random(5), modules=["CPX-E-16DI", "CPX-E-8DO"], dil1=True)
    model.apply("short_circuit", {"on": True, "channel": 1}, 2)
    model.apply("supply", {"out": 12.0})  # U_OUT low: an error of module 2 (Tab. 21)
    for t in range(1, 200):
        model.step(t * 1000)
    seen: list[Any] = []

    def walk(v: Any, depth: int = 0) -> None:
        if isinstance(v, VALUES):
            seen.append(v)
        if depth > 6:
            return
        items = v.values() if isinstance(v, dict) else v if isinstance(v, (list, tuple)) \
            else vars(v).values() if hasattr(v, "__dict__") and not callable(v) \
            else [getattr(v, name, None) for name in slot_names(type(v))]
        for x in items:
            walk(x, depth + 1)

    walk({k: v for k, v in vars(model).items() if k not in ("od", "rng", "events")})
    assert {type(v) for v in seen} >= {cls for cls in VALUES if cls.__name__ in (
        "ModuleType", "LedState", "ActiveError", "ModuleFault", "DiagMessage")}
    for cls in VALUES:
        assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen, cls
    for v in seen:
        hash(v)  # a list, dict or set inside would raise TypeError
