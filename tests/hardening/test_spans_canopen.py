"""Quiet spans of the CANopen node are exact (docs/canopen.md "Quiet spans").

``CanOpenNode.quiet_until`` / ``skip_to`` against stepping, two ways:

- a differential on single-drive rigs (span_runs.differential): a skipping rig and a plain one
  take the same random ops — the drive's commands (tests/hardening/test_still_steps.py
  ``random_op``), master frames (its ``FRAMES`` and more: NMT start / stop / resets,
  heartbeat times, guard time and life time factor with guarding requests, SYNC and its
  COB-ID, TPDO types 0 / 1 / 254 / 255 with event timers and inhibit times, TPDO3/4 switched
  on, RPDOs, RPDO COB-IDs moved and switched on / off, EMCY inhibit) — with stretches of
  1 .. 3000 steps, compared after each. The ServoDrive has no quiet_until of its own yet, so
  the drive here is a test subclass that says "quiet" exactly while its still step would be
  taken (``_still``, a repeat of a step that changed nothing: the step then moves only
  ``now_us`` / ``_t_us``, which is all its ``skip_to`` does). A drive on CANopen (the node's
  every NMT state) and one on Modbus (the silent node);
- directly on the default rig (master, three drives, their nodes; the drives plain): the
  nodes' spans in the idle states (pre-operational with heartbeat, silent nodes,
  operational with asynchronous TPDOs on an event timer, life guarding) — one rig stepped,
  its twin stepping every device but the node and calling the node's ``skip_to`` once —
  compared device by device, all the way down.

Reduced (CI, about 25 s): 2 x 20 rounds and the direct runs (spans followed up to 1 s, the node
compared); ``--full``: 6 x 400 rounds, spans up to 3 s, every device compared.
"""

from __future__ import annotations

import random
from typing import Any

import pytest
from span_runs import Op, deep_state, differential, lines
from test_still_steps import FRAMES, random_op

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec, parse_rig_spec
from devices.canopen.nmt import NmtState
from devices.canopen.node import CanOpenNode

ONE_DRIVE = """
[rig]
name = "one drive"
seed = {seed}
step_ms = 1

[[servo]]
id = "drive_co"
fieldbus = "{fieldbus}"
node_id = 2
ten_wired = true
ien_wired = true
"""


def sdo(index: int, sub: int, value: int, size: int) -> tuple[int, str, bool]:
    cmd = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
    raw = bytes((cmd,)) + index.to_bytes(2, "little") + bytes((sub,)) \
        + value.to_bytes(size, "little").ljust(4, b"\0")
    return 0x602, raw.hex(" "), False


MORE_FRAMES = (  # node 2 again
    (0x000, "01 02", False), (0x000, "01 00", False), (0x000, "02 02", False),
    (0x000, "81 02", False),
    sdo(0x1017, 0, 7, 2), sdo(0x1017, 0, 1000, 2), sdo(0x1017, 0, 0, 2),
    sdo(0x100C, 0, 10, 2), sdo(0x100D, 0, 0, 1), sdo(0x100C, 0, 0, 2),
    sdo(0x1015, 0, 100, 2), sdo(0x1005, 0, 0x81, 4), sdo(0x1005, 0, 0x80, 4),
    sdo(0x1800, 5, 100, 2), sdo(0x1800, 5, 0, 2), sdo(0x1800, 3, 500, 2),
    sdo(0x1800, 3, 0, 2), sdo(0x1800, 2, 254, 1), sdo(0x1800, 2, 255, 1),
    sdo(0x1800, 2, 1, 1), sdo(0x1800, 2, 0, 1),
    sdo(0x1802, 1, 0x382, 4), sdo(0x1802, 5, 250, 2), sdo(0x1803, 1, 0x482, 4),
    sdo(0x1803, 1, 0x8000_0482, 4), sdo(0x1A00, 0, 0, 1), sdo(0x1A00, 0, 1, 1),
    (0x081, "", False), (0x182, "", True), (0x202, "06 00 00 00 00 00", False),
    (0x202, "00 00 10 27 00 00", False),
    # RPDOs moved and switched on / off: the node takes frames on their current COB-IDs
    sdo(0x1400, 1, 0x201, 4), sdo(0x1400, 1, 0x202, 4), sdo(0x1401, 1, 0x302, 4),
    sdo(0x1401, 1, 0x8000_0302, 4), (0x201, "06 00 00 00 00 00", False),
    (0x302, "06 00 01", False),
)
# Frames that enable the drive (controlword 0x0F), kept rare: an enabled drive standing in
# mode 3 counts its speed-window timers every step and gives no span (docs/servo-drive.md).
ENABLING = frozenset({"2B 40 60 00 0F 00 00 00", "0F 00"})
ALL_FRAMES = tuple(f for f in FRAMES if f[1] not in ENABLING) + MORE_FRAMES


def one_drive_rig(fieldbus: str, seed: int) -> Rig:
    rig = build_rig(parse_rig_spec(ONE_DRIVE.format(seed=seed, fieldbus=fieldbus),
                                   "<one drive>"), state_dir=None)
    rig.advance(300)  # powered and booted: the node pre-operational (or silent)
    return rig


IDLE_ACTIONS = frozenset({"stop", "set_input", "inject_alarm", "clear_alarm", "alarm_reset",
                          "power", "save", "write_register", "write_object", "read_register",
                          "sync", "set_mode"})


def one_drive_op(rng: random.Random) -> Op:
    """A master frame, or one of the drive's commands that leave it disabled (see ENABLING;
    one in fifty an enable or a motion command all the same)."""
    if rng.random() < 0.45:
        cob_id, data, rtr = rng.choice(ALL_FRAMES)
        return "drive_co-can", "frame", {"cob_id": cob_id, "data": data, "rtr": rtr}
    moving = rng.random() < 0.02
    while True:
        target, action, args = random_op(rng)
        if target == "drive_co-can":
            continue
        if action == "controlword" and args["value"] & 0x0F == 0x0F and not moving:
            continue
        if moving or action in IDLE_ACTIONS:
            return "drive_co", action, args


@pytest.mark.parametrize("fieldbus, seed", [
    ("canopen", 1), ("modbus", 2),
    pytest.param("canopen", 3, marks=pytest.mark.full),
    pytest.param("canopen", 4, marks=pytest.mark.full),
    pytest.param("canopen", 5, marks=pytest.mark.full),
    pytest.param("modbus", 6, marks=pytest.mark.full)])
def test_spans_of_a_one_drive_rig_are_exact(fieldbus: str, seed: int, full: bool) -> None:
    rounds = 400 if full else 20
    skipped = differential(lambda: one_drive_rig(fieldbus, seed), one_drive_op, seed, rounds)
    assert skipped > rounds * 200  # most stretches of the idle drive were skipped


def test_spans_cover_the_operational_node() -> None:
    """An operational node with TPDO1 on an event timer and the heartbeat on: spans end at the
    event timer and the heartbeat, and are exact over many of them."""
    ops: list[Op] = [("drive_co-can", "frame", {"cob_id": c, "data": d, "rtr": r})
                     for c, d, r in (sdo(0x1017, 0, 70, 2), sdo(0x1800, 5, 45, 2),
                                     sdo(0x1800, 3, 100, 2), sdo(0x1802, 1, 0x382, 4),
                                     (0x000, "01 02", False))]
    it = iter(ops)

    def next_op(rng: random.Random) -> Op:
        return next(it, ("drive_co", "read_register", {"register": 5}))

    skipped = differential(lambda: one_drive_rig("canopen", 9), next_op, 9, 10,
                           lengths=(1, 20, 3000))
    assert skipped > 2000
    rig = one_drive_rig("canopen", 9)
    for op in ops:
        rig.apply(*op)
    rig.advance(500)
    node = rig.devices["drive_co-can"]
    assert node.state is NmtState.OPERATIONAL
    frames = node.take_frames()
    assert {f.can_id for f in frames} >= {0x182, 0x382, 0x702}
    until = node.quiet_until(1000)
    assert 1000 < until - node.now_us <= 45_000  # ends by TPDO1's event timer


# ---- the nodes of the default rig, directly --------------------------------------------------
def step_all_but(rig: Rig, skip: str) -> None:
    """Rig.step with one device left out."""
    now = rig.clock.tick()
    for device_id, device in rig.devices.items():
        if device_id != skip:
            device.step(now)
    rig._collect()


def span_by_skip_to(build: Any, setup: list[Op], node_id: str, warm: int, cap: int,
                    everything: bool, after_full: bool = False) -> int:
    """Two default rigs booted, given ``setup`` and ``warm`` steps; ``node_id``'s span stepped
    on one, skipped (skip_to) on the other while every other device steps; compared. A span
    that ends (before ``cap`` steps) ends tight: the next step is not a quiet one. Compared:
    the events, the snapshots and the node's deep state (its drive's with it), with
    ``everything`` every device's. The span."""
    rigs = [build(), build()]
    for rig in rigs:
        rig.SKIP_SPANS = False  # type: ignore[misc]
        rig.advance(300)  # the nodes booted (a frame before that is not heard)
        for op in setup:
            rig.apply(*op)
        rig.advance(warm)
        # after_full: start the span right after a full step (the heartbeat's), which leaves
        # no calm proven: the span's first step would prove it
        for _ in range(1_000 if after_full else 0):
            rig.step()
            if rig.devices[node_id]._calm_until == 0:
                break
        rig.take_events()
    stepped, skipping = rigs
    node = skipping.devices[node_id]
    assert isinstance(node, CanOpenNode)
    step_us = skipping.clock.step_us
    now = node.now_us
    until = node.quiet_until(step_us)
    assert until == stepped.devices[node_id].quiet_until(step_us)
    assert deep_state(stepped.devices[node_id]) == deep_state(node)  # no side effect
    steps = min((until - now) // step_us, cap)
    for _ in range(steps):
        step_all_but(skipping, node_id)
    node.skip_to(now + steps * step_us, step_us)
    events = stepped.advance(steps)
    assert lines(events) == lines(skipping.take_events())
    assert stepped.snapshot() == skipping.snapshot()
    for device_id in stepped.devices if everything else (node_id,):
        assert deep_state(stepped.devices[device_id]) == \
            deep_state(skipping.devices[device_id]), device_id
    if steps < cap:
        stepped.step()
        assert stepped.devices[node_id]._calm_until == 0  # a full step, or a frame sent
    return steps


CAP = 1_000  # steps of a span the direct test follows (x3 with --full)


def frame(cob_id: int, data: str = "", rtr: bool = False) -> Op:
    return "drive_co-can", "frame", {"cob_id": cob_id, "data": data, "rtr": rtr}


def default_rig() -> Rig:
    return build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)


@pytest.mark.parametrize("name, setup, node_id, least", [
    ("silent modbus node", [], "drive-can", CAP),
    ("silent ethercat node", [], "drive_ec-can", CAP),
    ("pre-operational, no heartbeat", [], "drive_co-can", CAP),
    ("pre-operational, heartbeat 200 ms", [frame(*sdo(0x1017, 0, 200, 2)[:2])],
     "drive_co-can", 10),
    ("pre-operational, heartbeat 200 ms, right after one",
     [frame(*sdo(0x1017, 0, 200, 2)[:2])], "drive_co-can", 150),
    ("operational, TPDO1 and TPDO3 async, event timers",
     [frame(*sdo(0x1800, 5, 300, 2)[:2]), frame(*sdo(0x1802, 1, 0x382, 4)[:2]),
      frame(*sdo(0x1802, 5, 170, 2)[:2]), frame(0, "01 02")], "drive_co-can", 10),
    ("operational, life guarding", [frame(*sdo(0x100C, 0, 100, 2)[:2]),
                                    frame(*sdo(0x100D, 0, 3, 1)[:2]), frame(0, "01 02"),
                                    frame(0x702, "", True)], "drive_co-can", 100),
    ("stopped", [frame(0, "02 02")], "drive_co-can", CAP),
])
def test_default_rig_nodes_skip_exactly(name: str, setup: list[Op], node_id: str,
                                        least: int, full: bool) -> None:
    spans = [span_by_skip_to(default_rig, setup, node_id, warm, CAP * (3 if full else 1),
                             full, after_full="right after" in name)
             for warm in ((120, 1_234, 2_900) if full else (120,))]
    assert min(spans) >= least, spans
