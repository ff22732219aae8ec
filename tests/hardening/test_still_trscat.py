"""The TRS-CAT's still parts change nothing (docs/trscat.md "Still steps").

A quiet step of the TRS-CAT reruns no slot whose last local cycle changed nothing and that
sees the same working state, field volts and outputs, evaluates no alarm causes and builds no
LED inputs but activity. That is exact or wrong: the same runs with ``SKIP_STILL`` = False on
the instance (every part of every step run) must give the same events, in the same order at
the same microsecond, the same snapshots and the same model state (seed 001 §3 debounce of 4
samples, §9.1.1 SM-event-missed counter, §9.3.5 / §9.3.6 outputs on error, §9.3.7 alarms).

- the example scenarios with the TRS-CAT on the line (CI: its three own and the pulled cable;
  ``--full``: every one whose rig has a TRS-CAT): events.jsonl lines and the snapshot at every
  checkpoint and at the end;
- a seeded random differential on a master + TRS-CAT rig, DC-SYNC and FREE-RUN (with a words
  expansion): every TRS-CAT action, object writes, the master's DC faults, lost frames, cables,
  slave power and target states, with idle stretches of up to 900 steps; every step's events,
  and after each stretch every snapshot and the TRS-CAT's whole state compared; the run must
  have skipped slot cycles (else it proved nothing);
- the steady step (docs/trscat.md "Step cost") against the full one, in a DC-SYNC rig whose
  frames are lost, dropped, late and whose SYNC0 is lost, so the step enters and leaves it often.
"""

from __future__ import annotations

import enum
import json
import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from still_runs import checkpoint_run, scenario_rig

from app.rig import Rig
from app.rig_config import build_rig, parse_rig_spec
from app.scenario import load_scenario
from devices.device import CommandError
from devices.od import SdoAbort
from devices.stillness import slot_names
from devices.trscat.device import TrsCat

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "static" / "scenarios").glob("*.toml"))
CI_SCENARIOS = ("trscat_expansion_mismatch", "trscat_outputs_fallback", "dc_sync_lost",
                "cable_pulled")


def no_skipping(rig: Rig) -> Rig:
    for device in rig.devices.values():
        if isinstance(device, TrsCat):
            device.SKIP_STILL = False
    return rig


def trscat_rig(path: Path) -> Rig:
    return scenario_rig(load_scenario(path))


def scenario_run(path: Path, skip: bool) -> tuple[list[str], dict[str, Any], int]:
    scenario = load_scenario(path)
    rig = scenario_rig(scenario)
    if not skip:
        no_skipping(rig)
    events, seen = checkpoint_run(scenario, rig)
    skipped = sum(d.skipped_slot_cycles for d in rig.devices.values() if isinstance(d, TrsCat))
    return events, seen, skipped


def _with_trscat(path: Path) -> bool:
    return any(isinstance(d, TrsCat) for d in trscat_rig(path).devices.values())


@pytest.mark.parametrize("path", [
    p if p.stem in CI_SCENARIOS else pytest.param(p, marks=pytest.mark.full)
    for p in SCENARIOS], ids=lambda p: p.stem)
def test_scenarios_are_the_same_without_skipping(path: Path) -> None:
    if not _with_trscat(path):
        pytest.skip("no TRS-CAT on this scenario's rig")
    events, snapshots, skipped = scenario_run(path, True)
    plain_events, plain_snapshots, plain_skipped = scenario_run(path, False)
    assert events == plain_events
    assert snapshots == plain_snapshots
    assert skipped > 1000 and plain_skipped == 0  # it did skip, and the switch switches


# ---- random differential -------------------------------------------------------------------
RIG = """
[rig]
name = "TRS-CAT still steps"
seed = {seed}
step_ms = 1

[master]
retry_interval_s = 0.5
line = ["trscat"]

[[trscat]]
id = "trscat"
expansions = {expansions}
configured = {expansions}
sync_mode = "{mode}"
"""
RIGS = {"dc": (["TRS-IO-E", "TRS-AN-E"], "dc"),
        "free_run": (["TRS-IO-E", "TRS-AN-E", "TRS-XX-E"], "free_run")}
Op = tuple[str, str, dict[str, Any]]
DIGITAL = ("trscat", "trscat/1")  # the integrated lines and the TRS-IO-E
ANALOG = "trscat/2"  # TRS-AN-E
WORDS = "trscat/3"  # TRS-XX-E (FREE-RUN rig only)
OBJECTS = (  # (index, sub, values): outputs on error, diagnosis flags, outputs, 0xF030
    (0xF700, 1, (0, 0x0005, 0xFFFF)), (0xF701, 1, (0, 0x000F, 0xFFFF)),
    (0xF710, 1, (0, 0x0030)), (0xF700, 3, (0, 0x8000, 0x0123)), (0xF701, 3, (0, 0xFFFF)),
    (0x10F3, 5, (0, 1, 0x0E)), (0x7000, 1, (0, 1)), (0x7010, 5, (0, 1)),
    (0x7020, 1, (-2000, 0, 3000)), (0xF030, 0, (2, 3)), (0xF030, 3, (0x414E2D45, 0)),
    (0x1C32, 1, (0, 2)),
)
FAULTS = (("FIELD_SUPPLY", "trscat"), ("FIELD_SUPPLY", "trscat/1"), ("AN_PLUS_12V", ANALOG),
          ("AN_MINUS_12V", ANALOG), ("CONFIG_ERROR", "trscat"),
          ("TRS_OVERCURRENT", "trscat"), ("SOFTWARE_ERROR", "trscat"))


OD_WRITE = "<od write>"  # straight into the object dictionary, as a master's process image


def random_ops(rng: random.Random, words: bool) -> list[Op]:
    """One operation, or a frame fault and an output write together: the outputs written
    then reach SM2 a few cycles later, in steps nothing touched (the latched image moves
    without a touch)."""
    op = random_op(rng, words)
    if rng.random() < 0.15:
        fault = rng.choice((("trscat", "drop_frames", {"count": rng.choice((1, 2, 3))}),
                            ("trscat", "frame_jitter", {"us": 1000}),
                            ("master", "dc_fault", {"kind": "jitter"})))
        return [fault, (rng.choice(DIGITAL), "set_output", {
            "channel": rng.randint(1, 16), "value": rng.randint(0, 1)})]
    return [op]


def random_op(rng: random.Random, words: bool) -> Op:
    digital = rng.choice(DIGITAL)
    channel = rng.randint(1, 16)
    fault, where = rng.choice(FAULTS)
    index, sub, values = rng.choice(OBJECTS)
    choices: list[tuple[float, Callable[[], Op]]] = [
        (6, lambda: (digital, "set_input", {"channel": channel, "on": rng.random() < 0.5})),
        (3, lambda: (digital, "set_input_voltage", {
            "channel": channel, "volts": rng.choice((0.0, 5.0, 11.0, 13.0, 15.0, 24.0))})),
        (2, lambda: (digital, "set_load", {"channel": channel,
                                           "amps": rng.choice((0.0, 0.3, 0.8, 9.0))})),
        (6, lambda: (digital, "set_output", {"channel": channel, "value": rng.randint(0, 1)})),
        (3, lambda: (ANALOG, "set_analog_input", {"channel": rng.randint(1, 4),
                                                  "volts": rng.uniform(-11.0, 11.0)})),
        (3, lambda: (ANALOG, "set_output", {"channel": rng.randint(1, 2),
                                            "value": rng.randint(-5000, 5000)})),
        (2, lambda: ("trscat", "field_supply", {"volts": rng.choice((24.0, 26.0, 17.0, 0.0,
                                                                     31.0))})),
        (1, lambda: ("trscat", "link", {"port": rng.choice(("in", "out")),
                                        "connected": rng.random() < 0.7})),
        (1, lambda: ("trscat", "power", {"on": rng.random() < 0.8})),
        (2, lambda: (where, "inject_fault", {"fault": fault})),
        (3, lambda: (where, "clear_fault", {"fault": fault})),
        (1, lambda: ("trscat", "drop_frames", {"count": rng.choice((1, 2, 3, 20))})),
        (1, lambda: ("trscat", "lose_sync0", {"lost": rng.random() < 0.5})),
        (1, lambda: ("trscat", "frame_jitter", {"us": rng.choice((0, 0, 400, 1000))})),
        (1, lambda: ("trscat", "set_sync_mode", {"mode": rng.choice(("dc", "free_run"))})),
        (1, lambda: ("trscat", "acknowledge_messages", {})),
        (4, lambda: ("trscat", "write_object", {"index": index, "sub": sub,
                                                "value": rng.choice(values)})),
        (3, lambda: ("trscat", OD_WRITE, {"index": index, "sub": sub,
                                          "value": rng.choice(values)})),
        (1, lambda: ("trscat", "read_object", {"index": 0xF100, "sub": rng.randint(1, 4)})),
        (0.5, lambda: (f"trscat/{rng.randint(1, 4)}", "plug", {
            "type": rng.choice(("TRS-IO-E", "TRS-AN-E", "TRS-AC-E"))})),
        (0.2, lambda: (f"trscat/{rng.randint(1, 4)}", "unplug", {})),
        (1, lambda: ("master", "dc_fault", {"kind": rng.choice(("drift", "jitter",
                                                                "sync0_lost"))})),
        (2, lambda: ("master", "clear_dc_fault", {})),
        (1, lambda: ("master", "lose_frames", {"count": rng.choice((1, 3, 150))})),
        (1, lambda: ("master", rng.choice(("pull_cable", "plug_cable")), {"cable": 0})),
        (1, lambda: ("master", "power_slave", {"position": 0, "on": rng.random() < 0.7})),
        (1, lambda: ("master", "set_target", {"state": rng.choice(("PREOP", "SAFEOP", "OP",
                                                                   "OP"))})),
        (0.5, lambda: ("master", "resync", {})),
    ]
    if words:
        choices.append((3, lambda: (WORDS, "set_input_word", {
            "channel": 1, "value": rng.choice((0, 1, 0xBEEF))})))
    weights = [w for w, _ in choices]
    return rng.choices([c for _, c in choices], weights)[0]()


def outcome(rig: Rig, op: Op) -> str:
    target, action, args = op
    try:
        if action == OD_WRITE:
            od = rig.devices[target].od  # type: ignore[attr-defined]
            if od is None:
                return "no dictionary"
            od.write(args["index"], args["sub"], args["value"])
            return "written"
        return repr(rig.apply(*op))
    except (CommandError, SdoAbort, KeyError) as exc:
        return f"refused: {exc}"


_BOOKKEEPING = frozenset({"SKIP_STILL", "_dirty", "_quiet", "_plan", "skipped_slot_cycles", "still",
                          "events", "od", "_step_in_full"})  # the last: a test's counter


def value_of(obj: Any) -> Any:
    """A plain value copy of a model object and its parts, without the skip bookkeeping."""
    if isinstance(obj, enum.Enum | int | float | str | bytes | bool) or obj is None:
        return obj
    if isinstance(obj, list | tuple):
        return [value_of(v) for v in obj]
    if isinstance(obj, dict):
        return sorted((repr(k), value_of(v)) for k, v in obj.items())
    if isinstance(obj, random.Random):
        return obj.getstate()
    if callable(obj):
        return None  # the ESM's bound emit
    attrs = vars(obj).items() if hasattr(obj, "__dict__") else \
        [(name, getattr(obj, name)) for name in slot_names(type(obj))]  # the ESM has slots
    return (type(obj).__name__, sorted((k, value_of(v)) for k, v in attrs
                                       if k not in _BOOKKEEPING))


def trscat_state(rig: Rig) -> Any:
    return value_of(rig.devices["trscat"])


def check_differential(name: str, seed: int, operations: int) -> int:
    expansions, mode = RIGS[name]
    spec = parse_rig_spec(RIG.format(seed=seed, expansions=json.dumps(expansions), mode=mode))
    skipping, plain = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    rng = random.Random(seed)
    for _ in range(2500):  # power-up detection, walk to OP: idle in OP is the usual state
        assert skipping.step() == plain.step()
    for _ in range(operations):
        ops = random_ops(rng, words=name == "free_run")
        for op in ops:
            assert outcome(skipping, op) == outcome(plain, op), op
            assert skipping.take_events() == plain.take_events(), op
        for _ in range(rng.choice((1, 2, 5, 20, 200, 900))):
            assert skipping.step() == plain.step(), op
        assert skipping.snapshot() == plain.snapshot(), op
        assert trscat_state(skipping) == trscat_state(plain), op
    trs = skipping.devices["trscat"]
    assert isinstance(trs, TrsCat)
    return trs.skipped_slot_cycles


@pytest.mark.parametrize(("name", "seed"), [
    ("dc", 1), ("free_run", 2),
    pytest.param("dc", 3, marks=pytest.mark.full),
    pytest.param("free_run", 4, marks=pytest.mark.full)])
def test_random_differential(name: str, seed: int, full: bool) -> None:
    skipped = check_differential(name, seed, 400 if full else 60)
    assert skipped > 2000  # the TRS-CAT did settle and skip


@pytest.mark.parametrize("name", list(RIGS))
def test_outputs_reaching_sm2_late_are_applied(name: str) -> None:
    """§9.1.1: a frame up to a cycle late misses its SYNC0 and is taken at the next one, a
    step that nothing touched; FREE-RUN latches at the frame, after the TRS-CAT's step. The
    outputs then differ from the ones applied although the step is quiet."""
    expansions, mode = RIGS[name]
    spec = parse_rig_spec(RIG.format(seed=9, expansions=json.dumps(expansions), mode=mode))
    rigs = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    rng = random.Random(9)
    for _ in range(2500):
        assert rigs[0].step() == rigs[1].step()
    for rig in rigs:
        rig.apply("trscat", "frame_jitter", {"us": 1000})
    for _ in range(300):
        op = (rng.choice(DIGITAL), "set_output", {"channel": rng.randint(1, 4),
                                                 "value": rng.randint(0, 1)})
        assert outcome(rigs[0], op) == outcome(rigs[1], op)
        for _ in range(rng.choice((2, 3, 8))):
            assert rigs[0].step() == rigs[1].step(), op
        assert trscat_state(rigs[0]) == trscat_state(rigs[1]), op
    assert rigs[0].snapshot() == rigs[1].snapshot()


def test_the_state_copy_sees_a_difference() -> None:
    """The comparison can fail: one debounce sample apart is a different state (§3)."""
    spec = parse_rig_spec(RIG.format(seed=1, expansions=json.dumps(RIGS["dc"][0]), mode="dc"))
    rigs = [build_rig(spec, state_dir=None) for _ in range(2)]
    for rig in rigs:
        for _ in range(2500):
            rig.step()
        rig.apply("trscat", "set_input", {"channel": 3, "on": True})
    rigs[0].step()
    assert trscat_state(rigs[0]) != trscat_state(rigs[1])


def _counting(real: Callable[..., Any], count: dict[str, int], name: str) -> Callable[..., Any]:
    def counted(*args: Any) -> Any:
        count[name] += 1
        return real(*args)
    return counted


@pytest.mark.parametrize("name", list(RIGS))
def test_idle_steps_take_the_short_ways(name: str) -> None:
    """Idle in OP the step neither copies latched images (no plc write since the last latch,
    §9.1.1 SM2 event) nor re-derives an unchanged sync state (§9.3.7), and in DC-SYNC it is the
    steady step (one SYNC0, one frame in time) without the full one: the shortcuts are taken,
    and with SKIP_STILL off they are not (the differential tests above prove them exact)."""
    expansions, mode = RIGS[name]
    spec = parse_rig_spec(RIG.format(seed=5, expansions=json.dumps(expansions), mode=mode))
    calls: list[dict[str, int]] = []
    for rig in (build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))):
        trs = rig.devices["trscat"]
        assert isinstance(trs, TrsCat)
        for _ in range(2500):
            rig.step()
        count = {"_latch_outputs": 0, "_check_sync": 0, "_step_in_full": 0}
        for method in count:
            setattr(trs, method, _counting(getattr(trs, method), count, method))
        for _ in range(1000):
            rig.step()
        rig.apply("trscat/1", "set_output", {"channel": 1, "value": 1})  # one write: latched
        for _ in range(10):
            rig.step()
        assert trs.rail[1] is not None and trs.rail[1].latched[0] == 1
        calls.append(count)
    skipping, plain = calls
    assert plain["_check_sync"] == 1010
    assert skipping["_check_sync"] == 0
    if mode == "dc":  # FREE-RUN latches at each frame (exchange_frame), not in the step
        assert plain["_latch_outputs"] == 1010 and skipping["_latch_outputs"] == 1
        # the steady step ("Step cost"): all but the write's step and the ones after it
        assert plain["_step_in_full"] == 1010 and skipping["_step_in_full"] <= 6


# ---- the steady step (docs/trscat.md "Step cost") ------------------------------------------
STEADY_OPS: tuple[Op, ...] = (  # what moves the sync unit, mostly without touching the TRS-CAT
    ("master", "lose_frames", {"count": 1}), ("master", "lose_frames", {"count": 2}),
    ("master", "lose_frames", {"count": 3}), ("master", "lose_frames", {"count": 150}),
    ("trscat", "drop_frames", {"count": 1}), ("trscat", "drop_frames", {"count": 2}),
    ("trscat", "frame_jitter", {"us": 400}), ("trscat", "frame_jitter", {"us": 1000}),
    ("trscat", "lose_sync0", {"lost": True}),
    ("trscat/1", "set_output", {"channel": 2, "value": 1}),
    ("trscat/1", "set_output", {"channel": 2, "value": 0}),
    ("trscat", "set_input", {"channel": 5, "on": True}),
    ("trscat", "set_input", {"channel": 5, "on": False}),
    ("master", "set_target", {"state": "SAFEOP"}),
)
HEAL: tuple[Op, ...] = (  # back to the steady case: one of them after most stretches
    ("trscat", "frame_jitter", {"us": 0}), ("trscat", "lose_sync0", {"lost": False}),
    ("master", "set_target", {"state": "OP"}),
)


@pytest.mark.parametrize("seed", [21, pytest.param(22, marks=pytest.mark.full)])
def test_steady_steps_differential(seed: int) -> None:
    """The steady step (one SYNC0 taking the one frame in time, quiet, OP, §9.1.1) against
    the full one: lost and late frames, SYNC0 lost, outputs, inputs and state changes in
    short stretches, so the unit enters and leaves the steady case often; every step's
    events, every stretch's snapshots and whole state compared."""
    spec = parse_rig_spec(RIG.format(seed=seed, expansions=json.dumps(RIGS["dc"][0]),
                                     mode="dc"))
    skipping, plain = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    trs = skipping.devices["trscat"]
    assert isinstance(trs, TrsCat)
    count = {"_step_in_full": 0}
    trs._step_in_full = _counting(trs._step_in_full, count, "_step_in_full")  # type: ignore
    rng = random.Random(seed)
    steps = 0
    for _ in range(2500):
        assert skipping.step() == plain.step()
    for _ in range(150):
        op = rng.choice(HEAL if rng.random() < 0.4 else STEADY_OPS)
        assert outcome(skipping, op) == outcome(plain, op), op
        assert skipping.take_events() == plain.take_events(), op
        for _ in range(rng.choice((1, 2, 3, 5, 10, 40, 300, 900))):  # long: back to OP
            assert skipping.step() == plain.step(), op
            steps += 1
        assert skipping.snapshot() == plain.snapshot(), op
        assert trscat_state(skipping) == trscat_state(plain), op
    steady = 2500 + steps - count["_step_in_full"]
    assert steady > steps // 4  # the steady step was taken, and left, many times
