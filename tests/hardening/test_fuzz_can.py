"""CAN fuzzing at the drive's CANopen node: random frames, all identifiers, all lengths, RTR.

Issue 7 "Hardening": no crash; SDO requests get correct answers or the right abort codes
(DS 301 as seed 004 ch. 4 "Servizio SDO" uses it; docs/canopen.md §SDO). One frame per 1 ms
step, so the NMT state a request meets is the state before that step. Most frames are uniform
over identifier 0..0x7FF, length 0..8 and RTR; a quarter are SDO requests to the node (every
command specifier, objects that exist and that do not); a few are NMT, SYNC and guarding
frames, so the node also runs stopped, reset and operational. The answers are judged by
can_oracle.py (the EDS's types, access and ranges; CiA 301 codes). Two benches: the pure node,
and the node behind the runtime's adapter (app/canopen_bus.py) on python-can's virtual bus.
Sizes: 12,000 + 2,000 frames in CI, 120,000 + 100,000 with ``--full``.
"""

from __future__ import annotations

import queue
import random
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

import can
from can_oracle import ABORT, SdoOracle

from app.canopen_bus import CanOpenBus
from devices.canopen.nmt import NmtState
from devices.canopen.node import CanOpenNode
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

SEED = 404
REDUCED, FULL = 12_000, 120_000
REDUCED_ADAPTER, FULL_ADAPTER = 2_000, 100_000
STEP_US = 1_000
SDO_RX, SDO_TX = 0x600, 0x580
COMMANDS = (0x40, 0x40, 0x2F, 0x2B, 0x27, 0x23, 0x22, 0x21, 0x20, 0x60, 0x70, 0x00, 0x10,
            0x01, 0x80, 0xA0, 0xC0, 0xE0)


@dataclass
class Bench:
    """The pure node: a frame is offered to it directly, its answers taken from its outbox."""

    drive: ServoDrive
    node: CanOpenNode
    t: int = 0

    def offer(self, can_id: int, data: bytes, rtr: bool, dlc: int | None) -> None:
        self.node.receive(can_id, data, rtr, dlc)

    def step(self) -> list[tuple[int, bytes]]:
        self.t += STEP_US
        self.drive.step(self.t)
        self.node.step(self.t)
        return [(f.can_id, f.data) for f in self.node.take_frames()]

    def close(self) -> None:
        pass


class AdapterBench(Bench):
    """The node behind the runtime's CAN adapter (app/canopen_bus.py) on python-can's virtual
    bus: a frame goes out on a master's bus, the adapter's notifier thread hands it over with
    ``submit``, and what the node sends comes back on the master's bus after the step."""

    def __init__(self, drive: ServoDrive, node: CanOpenNode) -> None:
        super().__init__(drive, node)
        channel = f"fuzz-can-{id(self)}"
        self.jobs: queue.Queue[tuple[Callable[[], Any], Future[Any]]] = queue.Queue()
        self.adapter = CanOpenBus([node], self._submit, interface="virtual", channel=channel)
        self.adapter.start()
        self.master = can.Bus(interface="virtual", channel=channel)

    def _submit(self, fn: Callable[[], Any]) -> Future[Any]:
        future: Future[Any] = Future()
        self.jobs.put((fn, future))
        return future

    def offer(self, can_id: int, data: bytes, rtr: bool, dlc: int | None) -> None:
        self.master.send(can.Message(arbitration_id=can_id, data=data, is_remote_frame=rtr,
                                     dlc=dlc if rtr else len(data), is_extended_id=False))
        fn, future = self.jobs.get(timeout=5)  # the adapter took it: run it as the runtime does
        future.set_result(fn())

    def step(self) -> list[tuple[int, bytes]]:
        self.t += STEP_US
        self.drive.step(self.t)
        self.node.step(self.t)
        self.adapter.on_step(self.t)
        frames = []
        while (msg := self.master.recv(timeout=0)) is not None:
            frames.append((msg.arbitration_id, bytes(msg.data)))
        return frames

    def close(self) -> None:
        self.adapter.stop()
        self.master.shutdown()


def _bench(kind: type[Bench] = Bench) -> Bench:
    drive = ServoDrive("servo", random.Random(3), DriveConfig(
        fieldbus="canopen", node_id=1, parameters={"n1": 8}), MemoryFlash())
    bench = kind(drive, CanOpenNode("servo-can", drive, random.Random(4)))
    for _ in range(60):  # power-on self test, Initialisation, boot-up
        bench.step()
    return bench


# ---- frames ----------------------------------------------------------------------------------
def _object(rng: random.Random, known: list[tuple[int, int]]) -> tuple[int, int]:
    """An object that exists, a neighbour of one, or anything."""
    roll = rng.random()
    index, sub = rng.choice(known)
    if roll < 0.6:
        return index, sub
    if roll < 0.75:
        return index, rng.choice((sub + 1, 0xFF, rng.randrange(256))) & 0xFF
    if roll < 0.85:
        return min(0xFFFF, index + rng.choice((-1, 1))), sub
    return rng.randrange(0x10000), rng.randrange(256)


def _sdo_request(rng: random.Random, known: list[tuple[int, int]]) -> bytes:
    command = rng.choice(COMMANDS) if rng.random() < 0.9 else rng.randrange(256)
    index, sub = _object(rng, known)
    body = bytes((command,)) + index.to_bytes(2, "little") + bytes((sub,)) + \
        bytes(rng.randrange(256) for _ in range(4))
    return body if rng.random() < 0.9 else body[:rng.randrange(1, 8)]


def _frame(rng: random.Random, node: CanOpenNode, known: list[tuple[int, int]]
           ) -> tuple[int, bytes, bool, int | None]:
    roll = rng.random()
    if roll < 0.25:
        return SDO_RX + node.node_id, _sdo_request(rng, known), False, None
    if roll < 0.28:  # NMT: start, stop, pre-op, reset node, reset communication, rubbish
        command = rng.choice((0x01, 0x01, 0x02, 0x80, 0x81, 0x82, rng.randrange(256)))
        target = rng.choice((0, node.node_id, rng.randrange(128)))
        return 0x000, bytes((command, target)), False, None
    if roll < 0.30:
        return 0x080, b"", False, None  # SYNC
    if roll < 0.31:
        return 0x700 + node.node_id, b"", True, 1  # node guarding request
    can_id = rng.randrange(0x800)
    dlc = rng.randrange(9)
    if rng.random() < 0.1:
        return can_id, b"", True, dlc
    return can_id, bytes(rng.randrange(256) for _ in range(dlc)), False, None


def _fuzz(kind: type[Bench], n: int) -> None:
    rng = random.Random(SEED)
    bench = _bench(kind)
    known = [(e.index, e.sub) for e in bench.node.dictionary]
    oracle, sdo_seen = SdoOracle(), bench.node.sdo
    failures: list[str] = []
    answered = aborted = 0
    for i in range(n):
        node = bench.node
        if not node.active:  # the drive left CANopen (c9 saved, reset): a fresh one
            bench.close()
            bench = _bench(kind)
            node = bench.node
        if node.sdo is not sdo_seen:
            oracle.reset()  # a new SDO server (reset communication): no transfer under way
        can_id, data, rtr, dlc = _frame(rng, node, known)
        state, node_id, sdo_seen = node.state, node.node_id, node.sdo
        bench.offer(can_id, data, rtr, dlc)
        sent = bench.step()
        if can_id != SDO_RX + node_id or rtr or not data:
            continue
        answers = [frame for cob_id, frame in sent if cob_id == SDO_TX + node_id]
        served = state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)
        if node.sdo is not sdo_seen or (state is NmtState.INITIALISATION and not answers):
            oracle.reset()
            continue  # it may boot within this step: silence is right, an answer is judged
        served = served or state is NmtState.INITIALISATION
        if not served or len(answers) > 1:
            if answers:
                failures.append(f"#{i} {state.label} {data.hex(' ')}: {len(answers)} answers")
            continue
        answer = answers[0] if answers else None
        problem = oracle.judge(node, data, answer)
        if problem:
            failures.append(f"#{i} {data.hex(' ')} -> {answer and answer.hex(' ')}: {problem}")
        if answer:
            answered += 1
            aborted += answer[0] == ABORT
    bench.close()
    assert not failures, f"{len(failures)} wrong SDO answers, first: {failures[:5]}"
    assert answered > 0.1 * n * 0.25  # most SDO requests were served
    assert 0 < aborted < answered  # both answers and aborts were judged
    assert oracle.confirmed > 0.01 * answered, oracle.confirmed  # downloads that landed


def test_random_frames_at_the_pure_node(full: bool) -> None:
    _fuzz(Bench, FULL if full else REDUCED)


def test_random_frames_through_the_bus_adapter(full: bool) -> None:
    _fuzz(AdapterBench, FULL_ADAPTER if full else REDUCED_ADAPTER)
