"""CAN fuzzing at the drive's pure CANopen node: random frames, all identifiers, all lengths, RTR.

Issue 7 "Hardening": no crash; SDO requests get correct answers or the right abort codes
(DS 301 as seed 004 ch. 4 "Servizio SDO" uses it; docs/canopen.md §SDO). One frame per 1 ms
step, so the NMT state a request meets is the state before that step. Most frames are uniform
over identifier 0..0x7FF, length 0..8 and RTR; a quarter are SDO requests to the node (every
command specifier, objects that exist and that do not); a few are NMT, SYNC and guarding
frames, so the node also runs stopped, reset and operational. Sizes: 12,000 frames in CI,
120,000 with ``--full``.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

from devices.canopen.bus_timing import CanFrame
from devices.canopen.nmt import NmtState
from devices.canopen.node import CanOpenNode
from devices.flash import MemoryFlash
from devices.od import AbortCode, SdoAbort, encode
from devices.servo.drive import DriveConfig, ServoDrive

SEED = 404
REDUCED, FULL = 12_000, 120_000
STEP_US = 1_000
SDO_RX, SDO_TX = 0x600, 0x580
ABORT = 0x80
NO_DATA = 0x0800_0024  # the library's "no data available" (an empty value)
KNOWN_CODES = {int(c) for c in AbortCode} | {NO_DATA}
VALUE_CODES = {AbortCode.LENGTH_TOO_HIGH, AbortCode.LENGTH_TOO_LOW, AbortCode.VALUE_RANGE,
               AbortCode.VALUE_TOO_HIGH, AbortCode.VALUE_TOO_LOW, AbortCode.TYPE_MISMATCH,
               AbortCode.GENERAL, AbortCode.CANNOT_STORE, AbortCode.CANNOT_STORE_LOCAL,
               AbortCode.CANNOT_STORE_STATE, AbortCode.UNSUPPORTED_ACCESS,
               AbortCode.NOT_MAPPABLE, AbortCode.PDO_TOO_LONG}
# 0x2000 (parameter access), 0x2005 / 0x2006 (variables by address): a write names another
# parameter or register, which may be read-only or missing (seed 004 ch. 4 "Procedura per la
# lettura e la scrittura dei parametri"; devices/servo/od_map.py IndirectAccess)
INDIRECT = frozenset({0x2000, 0x2005, 0x2006})
TARGET_CODES = {AbortCode.READ_ONLY, AbortCode.WRITE_ONLY, AbortCode.NO_OBJECT,
                AbortCode.NO_SUBINDEX}
# ccs of a request -> what may answer it besides an abort
CCS_DOWNLOAD_SEGMENT, CCS_DOWNLOAD, CCS_UPLOAD, CCS_UPLOAD_SEGMENT = 0x00, 0x20, 0x40, 0x60
CCS_ABORT, CCS_BLOCK_UPLOAD, CCS_BLOCK_DOWNLOAD, CCS_INVALID = 0x80, 0xA0, 0xC0, 0xE0
COMMANDS = (0x40, 0x40, 0x2F, 0x2B, 0x27, 0x23, 0x22, 0x21, 0x20, 0x60, 0x70, 0x00, 0x10,
            0x01, 0x80, 0xA0, 0xC0, 0xE0)


@dataclass
class Bench:
    drive: ServoDrive
    node: CanOpenNode
    t: int = 0

    def step(self) -> list[CanFrame]:
        self.t += STEP_US
        self.drive.step(self.t)
        self.node.step(self.t)
        return self.node.take_frames()


def _bench() -> Bench:
    drive = ServoDrive("servo", random.Random(3), DriveConfig(
        fieldbus="canopen", node_id=1, parameters={"n1": 8}), MemoryFlash())
    bench = Bench(drive, CanOpenNode("servo-can", drive, random.Random(4)))
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


# ---- the SDO oracle ----------------------------------------------------------------------------
def _expected_abort(node: CanOpenNode, index: int, sub: int, write: bool) -> int | None:
    """The abort an initiate request must get before its value matters (None: none)."""
    if (index, sub) not in node.dictionary:
        return int(AbortCode.NO_OBJECT if index not in node.dictionary.indices()
                   else AbortCode.NO_SUBINDEX)
    entry = node.dictionary.entry(index, sub)
    if write and not entry.access.writable:
        return int(AbortCode.READ_ONLY)
    if not write and not entry.access.readable:
        return int(AbortCode.WRITE_ONLY)
    return None


def _judge_sdo(node: CanOpenNode, request: bytes, answer: bytes) -> str | None:
    request = request.ljust(8, b"\0")
    ccs = request[0] & 0xE0
    index, sub = int.from_bytes(request[1:3], "little"), request[3]
    if len(answer) != 8:
        return f"answer of {len(answer)} bytes"
    code = int.from_bytes(answer[4:8], "little")
    aborted = answer[0] == ABORT
    if aborted and code not in KNOWN_CODES:
        return f"abort code 0x{code:08X} is not a DS 301 code"
    if ccs in (CCS_UPLOAD, CCS_BLOCK_UPLOAD, CCS_DOWNLOAD):
        write = ccs == CCS_DOWNLOAD
        if answer[1:4] != request[1:4]:
            return "the answer names another object"
        must = _expected_abort(node, index, sub, write)
        if must is not None:
            return None if aborted and code == must else f"expected abort 0x{must:08X}"
        if aborted:
            allowed = VALUE_CODES | (TARGET_CODES if index in INDIRECT else set())
            return None if write and code in allowed else f"unexpected abort 0x{code:08X}"
        if write:
            return None if answer[0] == 0x60 else "a download not confirmed with 0x60"
        return _judge_upload(node, index, sub, answer)
    if ccs in (CCS_BLOCK_DOWNLOAD, CCS_INVALID):
        return None if aborted and code == AbortCode.INVALID_COMMAND else \
            "a block download or an invalid command not aborted with 0x05040001"
    if aborted:  # a segment outside a transfer, a toggle error, the end of a download
        return None
    scs = answer[0] & 0xE0
    want = 0x00 if ccs == CCS_UPLOAD_SEGMENT else 0x20
    return None if scs == want else f"segment answered with scs 0x{scs:02X}"


def _judge_upload(node: CanOpenNode, index: int, sub: int, answer: bytes) -> str | None:
    entry = node.dictionary.entry(index, sub)
    try:
        data = encode(entry.dtype, node.dictionary.read(index, sub))
    except SdoAbort:
        return None  # the value cannot be read now (e.g. a drive that is off): abort expected
    if len(data) <= 4:
        want = bytes((0x43 | (4 - len(data)) << 2,)) + answer[1:4] + data.ljust(4, b"\0")
        return None if answer == want else f"upload {answer.hex(' ')}, expected {want.hex(' ')}"
    want = bytes((0x41,)) + answer[1:4] + len(data).to_bytes(4, "little")
    return None if answer == want else f"segmented upload start {answer.hex(' ')}"


def test_random_frames_at_the_pure_node(full: bool) -> None:
    rng = random.Random(SEED)
    bench = _bench()
    known = [(e.index, e.sub) for e in bench.node.dictionary]
    failures: list[str] = []
    answered = aborted = 0
    for i in range(FULL if full else REDUCED):
        node = bench.node
        if not node.active:  # the drive left CANopen (c9 saved, reset): a fresh one
            bench = _bench()
            node = bench.node
        can_id, data, rtr, dlc = _frame(rng, node, known)
        state, node_id = node.state, node.node_id
        node.receive(can_id, data, rtr, dlc)
        sent = bench.step()
        if can_id != SDO_RX + node_id or rtr or not data:
            continue
        answers = [f.data for f in sent if f.can_id == SDO_TX + node_id]
        served = state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)
        silent = data[0] & 0xE0 == CCS_ABORT  # a client's abort is never answered
        if state is NmtState.INITIALISATION:
            continue  # it may boot within this step: either way is right
        if len(answers) != (1 if served and not silent else 0):
            failures.append(f"#{i} {state.label} {data.hex(' ')}: {len(answers)} answers")
            continue
        if answers:
            answered += 1
            aborted += answers[0][0] == ABORT
            problem = _judge_sdo(node, data, answers[0])
            if problem:
                failures.append(f"#{i} {data.hex(' ')} -> {answers[0].hex(' ')}: {problem}")
    assert not failures, f"{len(failures)} wrong SDO answers, first: {failures[:5]}"
    assert answered > 0.1 * (FULL if full else REDUCED) * 0.25  # most SDO requests were served
    assert 0 < aborted < answered  # both answers and aborts were judged
