"""Skipping still steps changes nothing (docs/performance.md, benchmark 1).

The servo drive skips a step that repeats one which left its state exactly as it found it
(devices/servo/stillness.py) and the CANopen node skips a step in which nothing is due
(``CanOpenNode._quiet``). Both are exact or wrong: the same runs with skipping switched off
(``SKIP_STILL`` / ``SKIP_QUIET`` = False on the instances) must give the same events, in the
same order at the same microsecond, and the same snapshots.

- every example scenario and a scenario that works all three drives of the default rig (Modbus,
  CANopen, EtherCAT): events.jsonl lines and the snapshot at every checkpoint and at the end;
- a seeded random differential on two default rigs: commands to the drives, CANopen frames
  (NMT, SDO, heartbeat, guarding, SYNC, RPDO) and alarms, with idle stretches between them
  long enough for the drives to settle and skip; every event, every snapshot and every drive's
  full state (``state_key``) compared after each stretch;
- the drive alone at step lengths other than the rig's 1 ms (250 us .. 3.5 ms).

Reduced (CI, about 30-60 s): the three-drive scenario, 1 x 20 random operations
and 4 x 40 at other step lengths; ``--full`` (a few minutes): every example, 2 x 600 and 4 x 300.
"""

from __future__ import annotations

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
from devices.canopen.node import CanOpenNode
from devices.device import CommandError
from devices.flash import MemoryFlash
from devices.od import SdoAbort
from devices.servo.drive import DriveConfig, ServoDrive
from devices.servo.stillness import state_key

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "static" / "scenarios").glob("*.toml"))

THREE_DRIVES = """
[scenario]
name = "three drives, still and moving"
duration_s = 9

[[step]]
at = 0.2
target = "drive"
action = "enable"
on = true

[[step]]
at = 0.3
target = "drive"
action = "move"
position = 12000

[[step]]
at = 0.3
target = "drive_co-can"
action = "frame"
cob_id = 0
data = "01 02"

[[step]]
at = 0.4
target = "drive_co-can"
action = "frame"
cob_id = 0x602
data = "2B 17 10 00 64 00 00 00"

[[step]]
at = 0.5
target = "drive_co"
action = "enable"
on = true

[[step]]
at = 1.0
checkpoint = "moving"

[[step]]
at = 3.0
target = "drive_co"
action = "inject_alarm"
code = "16"

[[step]]
at = 3.5
target = "drive_co"
action = "clear_alarm"
code = "16"

[[step]]
at = 3.6
target = "drive_co"
action = "alarm_reset"

[[step]]
at = 4.0
target = "drive_ec"
action = "jog"
direction = 1

[[step]]
at = 4.5
target = "drive_ec"
action = "stop"

[[step]]
at = 5.0
checkpoint = "stopped"

[[step]]
at = 5.5
target = "drive"
action = "save"

[[step]]
at = 6.0
target = "drive"
action = "enable"
on = false

[[step]]
at = 6.5
target = "drive_co-can"
action = "frame"
cob_id = 0x602
data = "40 41 60 00 00 00 00 00"

[[step]]
at = 7.0
target = "drive"
action = "power"
on = false

[[step]]
at = 7.5
target = "drive"
action = "power"
on = true
"""


def no_skipping(rig: Rig) -> Rig:
    for device in rig.devices.values():
        if isinstance(device, ServoDrive):
            device.SKIP_STILL = False
        if isinstance(device, CanOpenNode):
            device.SKIP_QUIET = False
    return rig


def scenario_run(scenario: Any, skip: bool) -> tuple[list[str], dict[str, Any]]:
    rig = scenario_rig(scenario)
    if not skip:
        no_skipping(rig)
    return checkpoint_run(scenario, rig)


REDUCED_SCENARIOS: tuple[str, ...] = ()  # the three-drive scenario covers CI; all: --full


@pytest.mark.parametrize("path", [
    p if p.stem in REDUCED_SCENARIOS else pytest.param(p, marks=pytest.mark.full)
    for p in SCENARIOS], ids=lambda p: p.stem)
def test_example_scenarios_are_the_same_without_skipping(path: Path) -> None:
    scenario = load_scenario(path)
    assert scenario_run(scenario, True) == scenario_run(scenario, False)


def test_three_drives_scenario_is_the_same_without_skipping() -> None:
    scenario = parse_scenario(THREE_DRIVES, "<three drives>")
    events, snapshots = scenario_run(scenario, True)
    assert (events, snapshots) == scenario_run(scenario, False)
    kinds = {json.loads(line)["event"] for line in events}
    assert {"state", "alarm", "log", "checkpoint"} <= kinds  # the run did work the drives


# ---- random differential -------------------------------------------------------------------
Op = tuple[str, str, dict[str, Any]]
DRIVES = ("drive", "drive_co", "drive_ec")
FRAMES = (  # (cob_id, data, rtr) at node 2 (drive_co)
    (0x000, "01 02", False), (0x000, "80 02", False), (0x000, "02 02", False),
    (0x000, "82 02", False), (0x602, "2B 17 10 00 32 00 00 00", False),
    (0x602, "2B 17 10 00 00 00 00 00", False), (0x602, "40 41 60 00 00 00 00 00", False),
    (0x602, "2B 0C 10 00 64 00 00 00", False), (0x602, "2F 0D 10 00 03 00 00 00", False),
    (0x702, "", True), (0x080, "", False), (0x202, "0F 00", False), (0x202, "06 00", False),
    (0x602, "2B 40 60 00 0F 00 00 00", False), (0x602, "2F 60 60 00 03 00 00 00", False),
)


def random_op(rng: random.Random) -> Op:
    drive = rng.choice(DRIVES)
    choices: list[Callable[[], Op]] = [
        lambda: (drive, "enable", {"on": rng.random() < 0.7}),
        lambda: (drive, "move", {"position": rng.randint(-70_000, 70_000),
                                 "relative": rng.random() < 0.3}),
        lambda: (drive, "jog", {"direction": rng.choice((-1, 0, 1))}),
        lambda: (drive, "stop", {}),
        lambda: (drive, "start", {}),
        lambda: (drive, "home", {}),
        lambda: (drive, "set_mode", {"mode": rng.choice((1, 3, 6, 7, -1, -2, -127))}),
        lambda: (drive, "set_input", {"name": rng.choice(("ten", "ien", "latch", "start")),
                                      "value": rng.random() < 0.5}),
        lambda: (drive, "inject_alarm", {"code": rng.choice(("16", "9", "20"))}),
        lambda: (drive, "clear_alarm", {"code": rng.choice(("16", "9", "20"))}),
        lambda: (drive, "alarm_reset", {}),
        lambda: (drive, "jam_load", {"active": rng.random() < 0.5}),
        lambda: (drive, "power", {"on": rng.random() < 0.8}),
        lambda: (drive, "save", {}),
        lambda: (drive, "controlword", {"value": rng.choice((0, 6, 7, 0x0F, 0x1F, 0x80, 0x10F))}),
        lambda: (drive, "write_register", {"register": rng.choice((3, 4, 12, 13, 47)),
                                           "value": rng.randint(0, 20_000)}),
        lambda: (drive, "write_object", {"index": 0x2005, "sub": 0,
                                         "value": rng.choice((0x8006, 0x0005, 0x8046))}),
        lambda: (drive, "read_register", {"register": rng.randint(0, 60)}),
        lambda: (drive, "pulses", {"count": rng.randint(-5000, 5000)}),
        lambda: (drive, "master_encoder", {"rpm": rng.choice((0.0, 300.0, -120.0))}),
        lambda: (drive, "analog_input", {"volts": rng.choice((0.0, 2.5, -5.0))}),
        lambda: (drive, "sync", {}),
    ]
    if rng.random() < 0.3:
        cob_id, data, rtr = rng.choice(FRAMES)
        return "drive_co-can", "frame", {"cob_id": cob_id, "data": data, "rtr": rtr}
    return rng.choice(choices)()


def outcome(rig: Rig, op: Op) -> str:
    try:
        return repr(rig.apply(*op))
    except (CommandError, SdoAbort) as exc:
        return f"refused: {exc}"


def full_state(rig: Rig) -> tuple[Any, ...]:
    drives = tuple(state_key(d) for d in rig.devices.values() if isinstance(d, ServoDrive))
    return rig.snapshot(), drives


@pytest.mark.parametrize("seed", [11, pytest.param(12, marks=pytest.mark.full)])
def test_random_differential_on_the_default_rig(seed: int, full: bool) -> None:
    rng = random.Random(seed)
    spec = load_rig_spec(DEFAULT_RIG)
    skipping, plain = build_rig(spec, state_dir=None), no_skipping(build_rig(spec, state_dir=None))
    skipped_steps = 0
    for _ in range(600 if full else 20):
        op = random_op(rng)
        assert outcome(skipping, op) == outcome(plain, op), op
        assert skipping.take_events() == plain.take_events(), op
        for _ in range(rng.choice((1, 3, 20, 200, 900))):
            assert skipping.step() == plain.step(), op
            skipped_steps += sum(1 for d in skipping.devices.values()
                                 if isinstance(d, ServoDrive) and d._still.dt is not None)
        assert full_state(skipping) == full_state(plain), op
    assert skipped_steps > 1000  # the drives did settle and skip


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_drive_alone_at_other_step_lengths(seed: int, full: bool) -> None:
    rng = random.Random(seed)
    drives = [ServoDrive("servo", random.Random(7), DriveConfig(), MemoryFlash())
              for _ in range(2)]
    drives[1].SKIP_STILL = False
    rigs = [Rig("drive", {"drive": d}) for d in drives]
    t_us = 0
    for _ in range(300 if full else 40):
        op = random_op(rng)
        if op[0] == "drive_co-can":
            continue
        op = ("drive", op[1], op[2])
        assert outcome(rigs[0], op) == outcome(rigs[1], op), op
        dt = rng.choice((250, 1000, 2000, 3500))
        for _ in range(rng.choice((1, 10, 300))):
            t_us += dt
            for d in drives:
                d.step(t_us)
            assert drives[0].drain_events() == drives[1].drain_events(), op
        assert state_key(drives[0]) == state_key(drives[1]), op
        assert drives[0].snapshot() == drives[1].snapshot(), op
