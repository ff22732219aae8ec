"""The master's still steps change nothing (docs/ethercat-master.md "Still steps").

The EtherCAT master leaves out of a step the parts that would change nothing (the line
re-applied with the same cables and power, a slave served with nothing to do, the slaves'
states watched again unchanged, a quiet COMPENSATING cycle's DC step in the window;
``devices/master/still.py``). Exact or wrong: the same runs with
``SKIP_STILL = False`` on the master must give the same events, in the same order at the same
microsecond, the same snapshots and the same master state (every link's bookkeeping, the
physical links, the DC unit, the rng).

- the example scenarios on the EtherCAT line (cable pulled, DC sync lost, frames lost, the
  CPX-E-EC short circuit, the TRS-CAT expansion mismatch; every other example with ``--full``):
  events.jsonl lines and the snapshot at every checkpoint and at the end;
- a seeded random differential on two default rigs from power-on: the master's commands (cables,
  slave power, lost frames, DC faults, resync, targets, log styles) and the slaves' own (power,
  cables on their ports, faults that raise CoE emergencies, SYNC0 / frame faults, the drive's
  alarms and power), a wire master taking the line and giving it back; idle stretches of up
  to 900 steps; every step's events compared, the snapshots and the master's full state after
  each stretch, and the skipped parts counted.

Reduced (CI): five scenarios, 1 x 100 random operations; ``--full``: every example, 3 x 300.
"""

from __future__ import annotations

import enum
import random
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import pytest
from still_runs import checkpoint_run, scenario_rig

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario
from devices.device import CommandError
from devices.ethercat import AlState
from devices.master import EtherCatMaster
from devices.od import SdoAbort

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "static" / "scenarios").glob("*.toml"))
REDUCED = ("cable_pulled", "dc_sync_lost", "trscat_outputs_fallback", "cpx_short_circuit",
           "trscat_expansion_mismatch")
BOOT_STEPS = 4500  # power-on to every slave in OP takes about 3.5 s
NOTHING_SKIPPED = {"line": 0, "serve": 0, "watch": 0, "dc": 0}


def master_of(rig: Rig) -> EtherCatMaster:
    master = rig.devices["master"]
    assert isinstance(master, EtherCatMaster)
    return master


def no_skipping(rig: Rig) -> Rig:
    master_of(rig).SKIP_STILL = False
    return rig


PLAIN = (int, float, str, bool, type(None), enum.Enum)


def master_state(rig: Rig) -> dict[str, Any]:
    """Everything a master step can change, and each slave's plain attributes (frame times and
    counters the snapshots do not show; the rest of the slaves' state is in the snapshots)."""
    m = master_of(rig)
    links = [{k: v for k, v in vars(link).items() if k not in ("slave", "description")}
             for link in m.links]
    slaves = [{k: v for k, v in vars(link.slave).items() if isinstance(v, PLAIN)}
              for link in m.links]
    return {"links": links, "slaves": slaves, "phys": (m.phys_in, m.phys_out), "cables": m.cables,
            "dc": asdict(m.dc), "dc_hold": m.dc_hold, "rng": m.rng.getstate(),
            "counts": (m.frames, m.lost_frames, m.to_lose, m.next_cycle_us, m.network_op,
                       m.link_up, m._bursting, m.target), "log": list(m.log)}


# ---- scenarios ------------------------------------------------------------------------------
def scenario_run(path: Path, skip: bool) -> tuple[list[str], dict[str, Any]]:
    scenario = load_scenario(path)
    rig = scenario_rig(scenario)
    if "master" not in rig.devices:
        pytest.skip(f"{path.stem}: its rig has no EtherCAT master")
    if not skip:
        no_skipping(rig)
    events, seen = checkpoint_run(scenario, rig, lambda rig: (rig.snapshot(), master_state(rig)))
    counts = dict(vars(master_of(rig).skipped))
    if not master_of(rig)._dc_links:
        del counts["dc"]  # a line without DC slaves (the FastCAT line) has no DC cycle to skip
    seen["skipped"] = counts
    return events, seen


@pytest.mark.parametrize("path", [
    p if p.stem in REDUCED else pytest.param(p, marks=pytest.mark.full)
    for p in SCENARIOS], ids=lambda p: p.stem)
def test_example_scenarios_are_the_same_without_skipping(path: Path) -> None:
    events, seen = scenario_run(path, True)
    plain_events, plain_seen = scenario_run(path, False)
    skipped, plain_skipped = seen.pop("skipped"), plain_seen.pop("skipped")
    assert events == plain_events
    assert seen == plain_seen
    assert plain_skipped == {part: 0 for part in skipped}
    assert min(skipped.values()) > 1000, skipped  # the master did leave parts out


# ---- random differential --------------------------------------------------------------------
Op = tuple[str, str, dict[str, Any]]
POSITIONS = range(4)  # fastcat, trscat, cpx, drive_ec-ecat
TRS_FAULTS = ("SOFTWARE_ERROR", "CONFIG_ERROR")
EXTERNAL = "<external>"  # not a rig command: EtherCatMaster.set_external / external_request
CPX_FAULTS = ("sync_error", "watchdog", "undervoltage_out")


def random_op(rng: random.Random) -> Op:
    on = rng.random() < 0.65  # plug / power on more often than off: the line keeps working
    choices: list[Callable[[], Op]] = [
        lambda: ("master", "pull_cable", {"cable": rng.choice(POSITIONS)}),
        lambda: ("master", "plug_cable", {"cable": rng.choice(POSITIONS)}),
        lambda: ("master", "plug_cable", {"cable": rng.choice(POSITIONS)}),
        lambda: ("master", "power_slave", {"position": rng.choice(POSITIONS), "on": on}),
        lambda: ("master", "lose_frames", {"count": rng.choice((1, 3, 40, 600))}),
        lambda: ("master", "dc_fault", {"kind": rng.choice(("drift", "jitter", "sync0_lost"))}),
        lambda: ("master", "clear_dc_fault", {}),
        lambda: ("master", "resync", {}),
        lambda: ("master", "set_target", {"state": rng.choice(("OP", "OP", "SAFEOP", "PREOP",
                                                               "INIT"))}),
        lambda: ("master", "set_log_style", {"style": rng.choice(("twincat", "sirio"))}),
        lambda: (rng.choice(("fastcat", "trscat", "cpx", "drive_ec")), "power", {"on": on}),
        lambda: ("fastcat", "link", {"connected": on}),
        lambda: ("trscat", "link", {"port": rng.choice(("in", "out")), "connected": on}),
        lambda: ("cpx", "cable", {"port": rng.choice(("in", "out")), "connected": on}),
        lambda: ("drive_ec-ecat", "link", {"connected": on}),
        lambda: ("trscat", "inject_fault" if on else "clear_fault",
                 {"fault": rng.choice(TRS_FAULTS)}),
        lambda: ("trscat", "lose_sync0", {"lost": not on}),
        lambda: ("trscat", "drop_frames", {"count": rng.choice((0, 5, 200))}),
        lambda: ("trscat", "acknowledge_messages", {}),
        lambda: ("cpx", "inject_fault" if on else "clear_fault",
                 {"fault": rng.choice(CPX_FAULTS)}),
        lambda: ("cpx/2", "short_circuit", {"on": not on, "channel": 3}),
        lambda: ("cpx/1", "inject_fault" if on else "clear_fault", {"fault": "module_failure"}),
        lambda: ("fastcat", "inject_fault" if on else "clear_fault", {"fault": "coupler:0x04"}),
        lambda: ("drive_ec", "inject_alarm" if on else "clear_alarm",
                 {"code": rng.choice(("16", "9"))}),
        lambda: ("drive_ec", "alarm_reset", {}),
        lambda: ("master", EXTERNAL, {"on": rng.random() < 0.3,
                                      "position": rng.choice(POSITIONS),
                                      "state": rng.choice(("INIT", "PREOP", "SAFEOP", "OP"))}),
    ]
    return rng.choice(choices)()


def outcome(rig: Rig, op: Op) -> str:
    if op[1] == EXTERNAL:  # a wire master takes the line (issue 8) or gives it back
        master, args = master_of(rig), op[2]
        master.set_external(args["on"])
        if args["on"]:
            master.external_request(args["position"], AlState[args["state"]])
            master.external_frame(args["position"])
        return "external"
    try:
        return repr(rig.apply(*op))
    except (CommandError, SdoAbort) as exc:
        return f"refused: {exc}"


@pytest.mark.parametrize("seed", [21, pytest.param(22, marks=pytest.mark.full),
                                  pytest.param(23, marks=pytest.mark.full)])
def test_random_differential_on_the_default_rig(seed: int, full: bool) -> None:
    rng = random.Random(seed)
    spec = load_rig_spec(DEFAULT_RIG)
    skipping, plain = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    for _ in range(BOOT_STEPS):
        assert skipping.step() == plain.step()
    assert skipping.snapshot() == plain.snapshot()
    assert master_state(skipping) == master_state(plain)
    kinds: set[str] = set()
    for _ in range(300 if full else 100):
        op = random_op(rng)
        assert outcome(skipping, op) == outcome(plain, op), op
        assert skipping.take_events() == plain.take_events(), op
        for _ in range(rng.choice((1, 3, 20, 200, 900))):
            events = skipping.step()
            assert events == plain.step(), op
            kinds.update(type(e).__name__ for e in events if e.device == "master")
        assert skipping.snapshot() == plain.snapshot(), op
        assert master_state(skipping) == master_state(plain), op
    skipped = vars(master_of(skipping).skipped)
    assert vars(master_of(plain).skipped) == NOTHING_SKIPPED
    assert min(skipped.values()) > 1000, skipped  # the master did leave parts out
    # the run worked the paths the skipping must not hide: faults, losses, recoveries
    assert {"SlaveStateChange", "CommError", "LogLine", "StateChanged"} <= kinds, kinds


@pytest.mark.parametrize("timeout_us", [1_000_000, 2_000_000])
def test_transitions_under_way_timed_out_and_retried(timeout_us: int) -> None:
    """A slave's transition still under way is left unserved (``_check`` would do nothing):
    with a state timeout shorter than the FastCAT's internal-bus scan the master's INIT ->
    PREOP times out, is logged and retried, and a CNF press starts it over; the same steps
    with and without skipping."""
    spec = load_rig_spec(DEFAULT_RIG)
    skipping, plain = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    for rig in (skipping, plain):
        master_of(rig).state_timeout_us = timeout_us
    for i in range(14_000):
        if i == 9_000:
            for rig in (skipping, plain):
                rig.apply("fastcat", "hold_cnf", {"seconds": 3.0})
        assert skipping.step() == plain.step(), i
        if i % 500 == 0:
            assert master_state(skipping) == master_state(plain), i
    assert skipping.snapshot() == plain.snapshot()
    assert master_state(skipping) == master_state(plain)
    texts = [row["text"] for row in master_of(skipping).log]
    assert any("'INIT to PREOP' failed" in t for t in texts), texts  # the timeout was hit
    assert vars(master_of(skipping).skipped)["serve"] > 10_000
