"""The node's cheap steps are exact (docs/canopen.md "Step cost"; issue 7, benchmark 1).

Three fast paths, each compared with the plain one:

- a quiet step (``_quiet`` and the calm it proves until the next heartbeat or life-guard
  expiry) against full steps every time (``SKIP_QUIET = False``): a seeded random run of
  master frames from seed 004 ch. 4 — NMT, SDO writes of the heartbeat, guard time, life time
  factor and TPDO records (asynchronous types 254/255 with inhibit time and event timer,
  "Servizio PDO"), guarding requests, SYNC, RPDOs that change the statusword — and drive
  commands, with idle stretches; the same frames at the same instants, the same events;
- the calm itself: whenever a step took it, a full evaluation of ``_quiet`` agrees;
- ``Pdo.pack_planned`` against ``Pdo.pack`` for every mapping the node accepts, and for
  objects that do not exist.
"""

from __future__ import annotations

import contextlib
import random
from typing import Any

import pytest
from canopen_bench import Bench, make_bench

from devices.canopen.guarding import NodeGuard
from devices.canopen.pdo import DEFAULT_TPDO_MAPS, Pdo
from devices.device import CommandError
from devices.od import SdoAbort

NODE = 1


def sdo_write(index: int, sub: int, value: int, size: int) -> tuple[int, bytes]:
    cmd = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
    data = bytes((cmd,)) + index.to_bytes(2, "little") + bytes((sub,)) \
        + value.to_bytes(size, "little").ljust(4, b"\0")
    return 0x600 + NODE, data


def random_frame(rng: random.Random) -> tuple[int, bytes, bool]:
    tpdo = rng.randrange(4)
    choices: list[tuple[int, bytes, bool]] = [
        (0x000, bytes((rng.choice((0x01, 0x80, 0x02, 0x81, 0x82)), NODE)), False),
        (0x000, bytes((0x01, NODE)), False),  # start: mostly Operational, where TPDOs go
        (*sdo_write(0x1017, 0, rng.choice((0, 7, 50, 120)), 2), False),
        (*sdo_write(0x100C, 0, rng.choice((0, 10, 40)), 2), False),
        (*sdo_write(0x100D, 0, rng.choice((0, 2, 3)), 1), False),
        (*sdo_write(0x1800 + tpdo, 2, rng.choice((254, 255, 0, 1, 3)), 1), False),
        (*sdo_write(0x1800 + tpdo, 3, rng.choice((0, 20, 300)), 2), False),
        (*sdo_write(0x1800 + tpdo, 5, rng.choice((0, 5, 30)), 2), False),
        (*sdo_write(0x1800 + tpdo, 1, rng.choice((0x180, 0x280, 0x380, 0x480)) + NODE
                    | rng.choice((0, 0x8000_0000)), 4), False),
        (0x700 + NODE, b"", True),  # guarding request
        (0x080, b"", False),  # SYNC
        (0x200 + NODE, rng.choice((0x0006, 0x0007, 0x000F, 0x0080, 0)).to_bytes(2, "little")
         + b"\0\0\0\0", False),
        (*sdo_write(0x1014, 0, 0x80 + NODE | rng.choice((0, 0x8000_0000)), 4), False),
        (*sdo_write(0x1015, 0, rng.choice((0, 100)), 2), False),
    ]
    return rng.choice(choices)


def drive_command(bench: Bench, rng: random.Random) -> None:
    action, args = rng.choice((("enable", {"on": True}), ("enable", {"on": False}),
                               ("power", {"on": False}), ("power", {"on": True}),
                               ("inject_alarm", {"code": "4"}), ("clear_alarm", {"code": "4"}),
                               ("alarm_reset", {})))
    with contextlib.suppress(CommandError):
        bench.drive.apply(action, args)


def record(bench: Bench, taken: list[tuple[int, int]]) -> list[Any]:
    """Every frame with its instant and the step it was taken at, and every event."""
    frames = [(f.can_id, f.data, f.rtr, f.t_us, at) for f, (at, _) in zip(bench.sent, taken,
                                                                          strict=True)]
    return frames + [e.to_record() for e in bench.events]


def step(bench: Bench, taken: list[tuple[int, int]], check_calm: bool = False) -> bool:
    """Bench.step, noting the step each frame was taken at; with ``check_calm``, before the
    node steps, that a step taking the calm would find ``_quiet`` true. True: it took it."""
    node, drive = bench.node, bench.drive
    bench.t_us += 1000
    drive.step(bench.t_us)
    power = drive.latched_at_power_up if drive.powered else None
    calm = power is node._power_seen and node.active and bench.t_us < node._calm_until \
        and drive.alarms.latched == node._known_alarms
    if calm and check_calm:
        assert node._quiet(bench.t_us), bench.t_us
    node.step(bench.t_us)
    frames = node.take_frames()
    bench.sent += frames
    taken += [(bench.t_us, f.can_id) for f in frames]
    bench.events += drive.drain_events() + node.drain_events()
    return calm


def random_run(seed: int, skip: bool, check_calm: bool = False) -> tuple[list[Any], int]:
    """The frames and events of a random run, and how many TPDOs went out."""
    bench = make_bench(boot=False)
    bench.node.SKIP_QUIET = skip
    rng = random.Random(seed)
    calm_steps = 0
    taken: list[tuple[int, int]] = []
    for _ in range(120):
        roll = rng.random()
        if roll < 0.75:
            can_id, data, rtr = random_frame(rng)
            bench.send(can_id, data, rtr)
        elif roll < 0.85:
            drive_command(bench, rng)
        for _ in range(rng.choice((1, 2, 5, 30, 200))):
            calm_steps += step(bench, taken, check_calm)
    if check_calm:
        assert calm_steps > 100  # the calm was taken, and checked
    tpdos = sum(f.can_id in (0x181, 0x281, 0x381, 0x481) for f in bench.sent)
    return record(bench, taken), tpdos


@pytest.mark.parametrize("seed", range(4))
def test_quiet_steps_are_the_same_as_full_steps(seed: int) -> None:
    fast, tpdos = random_run(seed, True)
    assert (fast, tpdos) == random_run(seed, False)
    assert tpdos > 0  # the asynchronous TPDO path ran


def timed_run(skip: bool) -> tuple[list[Any], int]:
    """Operational with asynchronous TPDOs on their event timer and inhibit time, and one
    that follows a moving drive (TPDO4: statusword + velocity actual value)."""
    bench = make_bench()
    bench.node.SKIP_QUIET = skip
    taken: list[tuple[int, int]] = [(0, f.can_id) for f in bench.sent]  # the boot-up

    def run(ms: int) -> None:
        for _ in range(ms):
            step(bench, taken, check_calm=skip)

    for can_id, data in (sdo_write(0x1800, 5, 7, 2), sdo_write(0x1800, 3, 30, 2),
                         sdo_write(0x1803, 1, 0x480 + NODE, 4),
                         sdo_write(0x1803, 3, 50, 2), sdo_write(0x1017, 0, 25, 2)):
        bench.send(can_id, data)
        run(3)
    bench.send(0x000, bytes((0x01, NODE)))
    run(200)
    for action, args in (("enable", {"on": True}), ("jog", {"direction": 1}),
                         ("jog", {"direction": 0}), ("enable", {"on": False})):
        bench.drive.apply(action, args)
        run(400)
    tpdos = sum(f.can_id in (0x181, 0x481) for f in bench.sent)
    return record(bench, taken), tpdos


def test_timed_tpdos_are_the_same_as_with_full_steps() -> None:
    fast, tpdos = timed_run(True)
    assert (fast, tpdos) == timed_run(False)
    assert tpdos > 200


@pytest.mark.parametrize("seed", range(2))
def test_a_calm_step_is_a_quiet_one(seed: int) -> None:
    random_run(seed + 10, True, check_calm=True)


def test_an_idle_operational_node_sends_its_tpdo_once() -> None:
    """Asynchronous TPDO1 (type 255, no event timer): once on entering Operational, then
    only on a change ("Servizio PDO")."""
    bench = make_bench()
    bench.nmt(0x01)
    bench.take()
    bench.run(500)
    assert [f.can_id for f in bench.take()] == []
    bench.send(0x201, (0x0006).to_bytes(2, "little") + b"\0\0\0\0")
    bench.run(20)
    assert [f.can_id for f in bench.take()] == [0x181]


@pytest.mark.parametrize("guard_ms,factor,asked_at", [
    (0, 0, None), (10, 0, 5_000), (10, 3, None), (10, 3, 5_000), (40, 2, 0)])
def test_expiry_at_is_where_expires_by_turns(guard_ms: int, factor: int,
                                             asked_at: int | None) -> None:
    guard = NodeGuard(guard_time_ms=guard_ms, life_time_factor=factor)
    if asked_at is not None:
        guard.request(asked_at)
    at = guard.expiry_at()
    for now in range(0, 200_000, 997):
        assert guard.expires_by(now) == (at is not None and now >= at)
    if at is not None:
        assert not guard.expires_by(at - 1) and guard.expires_by(at)


def mappings() -> list[tuple[int, ...]]:
    objects = (0x6041_0010, 0x6061_0008, 0x6064_0020, 0x606C_0020, 0x6077_0010,
               0x1001_0008, 0x6040_0010)
    out = [*DEFAULT_TPDO_MAPS, ()]
    rng = random.Random(3)
    for _ in range(20):
        out.append(tuple(rng.sample(objects, rng.randint(1, 3))))
    return out


@pytest.mark.parametrize("mapping", mappings(), ids=lambda m: "+".join(f"{e:08X}" for e in m))
def test_planned_pack_is_pack(mapping: tuple[int, ...]) -> None:
    bench = make_bench()
    dictionary = bench.node.dictionary
    pdo = Pdo(1, False, 0x181, entries=[*mapping, *[0] * (8 - len(mapping))],
              count=len(mapping))

    def plain() -> Any:
        try:
            return pdo.pack(dictionary.entry, dictionary.peek)
        except (SdoAbort, CommandError) as exc:
            return repr(exc)

    def planned() -> Any:
        try:
            return pdo.pack_planned(dictionary)
        except (SdoAbort, CommandError) as exc:
            return repr(exc)

    for cw in (0x0006, 0x0007, 0x000F, 0x0000):
        bench.drive.apply("enable", {"on": cw == 0x000F})
        bench.run(5)
        assert planned() == plain()
        assert planned() == plain()  # the plan made, then used
    pdo.entries[0], pdo.count = 0x7FFF_0010, max(pdo.count, 1)  # an object that does not exist
    assert planned() == plain()
    assert "SdoAbort" in planned()
