"""Modbus fuzzing over the real TCP server (DriveModbusServer), MBAP and RTU-over-TCP framing.

Two phases per framing, each request on a connection of its own (many at once):

1. exact: well-framed ADUs around fuzzed PDUs that change nothing (reads, and requests the
   oracle says must be refused). The drives' state is therefore the same before every
   request, so the oracle (modbus_oracle.py, independent of the code under test) judges each
   answer on the wire against the pristine line: the correct reply, exception 02 where an
   address names nothing, or nothing for the documented reasons; and the drives end as they
   started.
2. broken framing: bad MBAP headers (protocol id, length), bad CRCs, truncated ADUs, garbage.
   Whatever comes back must be a well-formed frame carrying a response or exception 02; the
   server keeps answering (a probe on a fresh connection gets its reply: no crash, no hang).

The server reaches the drives through a one-thread executor (a simulation thread that does not
step): every request is served in that thread, as in the runtime, and nothing varies with time.
Sizes: 240 exact + 120 broken per framing in CI; 3,000 + 1,500 with ``--full``.
"""

from __future__ import annotations

import copy
import random
import selectors
import socket
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

import pytest
from fuzz_modbus import FC03, FC06, FC16, judge, line_state, requests
from modbus_oracle import due
from pymodbus.framer import FramerRTU

from app.modbus.pdu import Exception02, Outcome, Reply, Silence, serve_line
from app.modbus.server import DriveModbusServer
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

SEED = 7
NODES = (1, 5)
BATCH = 40  # connections open at once
REPLY_WAIT_S = 10.0  # generous: a loaded CI machine; silence is judged after every reply came
QUIET_S = 0.3  # after the last expected reply: time for an unexpected one to show up
PROBE = bytes.fromhex("03 8005 0002")  # R05 status word of node 1


def _pristine() -> list[ServoDrive]:
    drives = [ServoDrive(f"servo{n}", random.Random(n), DriveConfig(node_id=n), MemoryFlash())
              for n in NODES]
    for drive in drives:
        drive.step(100_000)  # past the power-on self test
    return drives


def _exact_cases(rng: random.Random, template: list[ServoDrive], n: int
                 ) -> list[tuple[int, bytes]]:
    """(unit, PDU) of fuzzed requests the oracle says leave the line as it was."""
    start = line_state(template)
    cases: list[tuple[int, bytes]] = []
    for unit, pdu in requests(rng, 50 * n, NODES):
        if not pdu or due(start, unit, pdu).kind == "write":
            continue  # an empty PDU cannot be framed; a write changes the line
        if unit == 0 and pdu[0] in (FC06, FC16):
            continue  # a broadcast write is applied
        cases.append((unit, pdu))
        if len(cases) == n:
            break
    return cases


def _outcome(pdu: bytes | None) -> Outcome:
    """The answer on the wire as the PDU layer's outcome (a malformed one as a Reply)."""
    if not pdu:
        return Silence("nothing on the wire")
    if len(pdu) == 2 and pdu[0] & 0x80 and pdu[1] == 0x02:
        return Exception02(pdu[0] & 0x7F)
    return Reply(pdu)


# ---- framing ---------------------------------------------------------------------------------
def _adu(framer: str, unit: int, pdu: bytes, tid: int) -> bytes:
    if framer == "rtu":
        body = bytes((unit,)) + pdu
        return body + FramerRTU.compute_CRC(body).to_bytes(2, "big")
    return tid.to_bytes(2, "big") + b"\0\0" + (len(pdu) + 1).to_bytes(2, "big") + \
        bytes((unit,)) + pdu


def _broken_adu(rng: random.Random, framer: str, unit: int, pdu: bytes, tid: int) -> bytes:
    adu = bytearray(_adu(framer, unit, pdu, tid))
    roll = rng.random()
    if roll < 0.25:
        return bytes(rng.randrange(256) for _ in range(rng.randint(1, 40)))
    if roll < 0.5:
        return bytes(adu[:rng.randrange(1, len(adu))])
    if framer == "rtu":
        adu[-1 - rng.randrange(2)] ^= 1 << rng.randrange(8)  # CRC error
    elif roll < 0.75:
        adu[2:4] = rng.randrange(1, 0x10000).to_bytes(2, "big")  # protocol id not 0
    else:
        adu[4:6] = rng.randrange(0x10000).to_bytes(2, "big")  # length that lies
    return bytes(adu)


def _pdu_of(framer: str, frame: bytes) -> bytes | None:
    """The PDU of a reply frame, None if the frame itself is malformed."""
    if framer == "rtu":
        if len(frame) < 4 or FramerRTU.compute_CRC(frame[:-2]).to_bytes(2, "big") != frame[-2:]:
            return None
        return frame[1:-2]
    if len(frame) < 8 or frame[2:4] != b"\0\0" or int.from_bytes(frame[4:6], "big") != \
            len(frame) - 6:
        return None
    return frame[7:]


def _header_problem(framer: str, frame: bytes, unit: int, tid: int) -> str | None:
    """An answer must name the request's unit and (MBAP) its transaction id."""
    if not frame:
        return None
    unit_at = 0 if framer == "rtu" else 6
    if frame[unit_at] != unit:
        return f"answered for unit {frame[unit_at]}"
    if framer != "rtu" and frame[:2] != tid.to_bytes(2, "big"):
        return f"answered with transaction id {frame[:2].hex()}"
    return None


def _well_formed_reply(pdu: bytes) -> bool:
    """A response or exception 02 of FC 03 / 06 / 16, by shape alone."""
    if len(pdu) == 2 and pdu[0] in (0x83, 0x86, 0x90):
        return pdu[1] == 0x02
    if pdu[:1] == bytes((FC03,)):
        return len(pdu) >= 3 and pdu[1] % 2 == 0 and len(pdu) == 2 + pdu[1]
    return pdu[:1] in (bytes((FC06,)), bytes((FC16,))) and len(pdu) == 5


# ---- the line --------------------------------------------------------------------------------
@contextmanager
def _served(framer: str, drives: list[ServoDrive]) -> Iterator[DriveModbusServer]:
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="fuzz-sim") as sim:
        server = DriveModbusServer(drives, sim.submit, host="127.0.0.1", port=0, framer=framer)
        server.start_in_thread()
        try:
            yield server
        finally:
            server.stop_in_thread()


def _exchange(port: int, frames: list[bytes], expect_reply: list[bool]) -> list[bytes]:
    """Each frame on its own connection, all at once; the bytes that came back on each."""
    socks = [socket.create_connection(("127.0.0.1", port), timeout=REPLY_WAIT_S)
             for _ in frames]
    got = [b""] * len(frames)
    with selectors.DefaultSelector() as sel:
        for i, (sock, frame) in enumerate(zip(socks, frames, strict=True)):
            sock.sendall(frame)
            sock.setblocking(False)
            sel.register(sock, selectors.EVENT_READ, i)
        deadline = time.monotonic() + REPLY_WAIT_S
        quiet_from: float | None = None
        while True:
            now = time.monotonic()
            if quiet_from is None and all(got[i] or not e for i, e in enumerate(expect_reply)):
                quiet_from = now
            end = deadline if quiet_from is None else min(deadline, quiet_from + QUIET_S)
            if now >= end or not sel.get_map():
                break
            for key, _ in sel.select(end - now):
                chunk = key.fileobj.recv(512)  # type: ignore[union-attr]
                got[key.data] += chunk
                if not chunk:
                    sel.unregister(key.fileobj)
    for sock in socks:
        sock.close()
    return got


def _chunks(items: list, size: int) -> Iterator[list]:
    for i in range(0, len(items), size):
        yield items[i:i + size]


@pytest.mark.parametrize("framer", ["socket", "rtu"])
def test_exact_answers_over_tcp(framer: str, full: bool) -> None:
    rng = random.Random(SEED)
    template = _pristine()
    cases = _exact_cases(rng, template, 3_000 if full else 240)
    drives = copy.deepcopy(template)
    start = line_state(template)
    kinds: set[str] = set()
    with _served(framer, drives) as server:
        for batch in _chunks(list(enumerate(cases)), BATCH):
            frames = [_adu(framer, unit, pdu, 1 + i) for i, (unit, pdu) in batch]
            expect = [due(start, unit, pdu).kind != "silence" for _i, (unit, pdu) in batch]
            got = _exchange(server.port, frames, expect)
            for (i, (unit, pdu)), answer in zip(batch, got, strict=True):
                pdu_back = _pdu_of(framer, answer) if answer else b""
                outcome = _outcome(pdu_back)
                kinds.add(type(outcome).__name__)
                problem = "a malformed frame" if pdu_back is None else \
                    _header_problem(framer, answer, unit, 1 + i) or \
                    judge(template, unit, pdu, outcome, start)
                assert problem is None, \
                    f"#{i} unit {unit} {pdu.hex(' ')}: got {answer.hex(' ')}: {problem}"
    assert line_state(drives) == start
    assert kinds == {"Reply", "Exception02", "Silence"}


@pytest.mark.parametrize("framer", ["socket", "rtu"])
def test_broken_framing_over_tcp(framer: str, full: bool) -> None:
    rng = random.Random(SEED + 1)
    drives = _pristine()
    cases = list(requests(rng, 1_500 if full else 120, NODES))
    frames = [_broken_adu(rng, framer, unit, pdu or b"\x03", 1 + i)
              for i, (unit, pdu) in enumerate(cases)]
    with _served(framer, drives) as server:
        for batch in _chunks(frames, BATCH):
            got = _exchange(server.port, batch, [False] * len(batch))
            for frame, answer in zip(batch, got, strict=True):
                if not answer:
                    continue
                pdu = _pdu_of(framer, answer)
                assert pdu is not None and _well_formed_reply(pdu), \
                    f"{frame.hex(' ')} -> malformed answer {answer.hex(' ')}"
        # still serving: a probe on a fresh connection gets the right answer
        probe = _exchange(server.port, [_adu(framer, 1, PROBE, 0xBEEF)], [True])[0]
    want = serve_line(drives, 1, PROBE)  # the server is gone: this thread may touch the drives
    assert isinstance(want, Reply)
    assert probe == _adu(framer, 1, want.pdu, 0xBEEF)


# ---- pipelining: what a bad MBAP header does to the frames behind it --------------------------
BAD_MBAP = {  # header fields that break the MBAP framing (Implementation Guide: "invalid")
    "protocol id 1": {"proto": 1}, "protocol id 0xFFFF": {"proto": 0xFFFF},
    "length 0": {"length": 0}, "length 1": {"length": 1}, "length 255": {"length": 255},
    "length 0xFFFF": {"length": 0xFFFF},
}


def _mbap(unit: int, pdu: bytes, tid: int, proto: int = 0, length: int | None = None) -> bytes:
    length = len(pdu) + 1 if length is None else length
    return tid.to_bytes(2, "big") + proto.to_bytes(2, "big") + length.to_bytes(2, "big") + \
        bytes((unit,)) + pdu


def _stream(port: int, frames: list[bytes], gap_s: float, expect: int) -> tuple[bytes, bool]:
    """Send ``frames`` on one connection (one write, or one per frame ``gap_s`` apart); the
    bytes that came back and whether the server closed the connection. Read until the server
    closes, or until ``expect`` replies came and no more came for a quiet spell: a quiet
    spell alone ended the read while a loaded machine still worked on owed replies (a CI run
    saw the two before a bad header "not answered")."""
    got, closed = b"", False
    with socket.create_connection(("127.0.0.1", port), timeout=REPLY_WAIT_S) as sock:
        try:
            if gap_s:
                for frame in frames:
                    sock.sendall(frame)
                    time.sleep(gap_s)
            else:
                sock.sendall(b"".join(frames))
        except OSError:
            closed = True  # reset while sending: closed
        deadline = time.monotonic() + REPLY_WAIT_S
        while not closed:
            enough = len(_answered_tids(got)) >= expect
            wait = QUIET_S * 3 if enough else deadline - time.monotonic()
            if wait <= 0:
                break
            sock.settimeout(wait)
            try:
                chunk = sock.recv(65536)
            except TimeoutError:
                break
            except OSError:
                chunk = b""
            closed, got = not chunk, got + chunk
    return got, closed


def _answered_tids(stream: bytes) -> list[int]:
    tids, at = [], 0
    while at + 6 <= len(stream):
        size = 6 + int.from_bytes(stream[at + 4:at + 6], "big")
        tids.append(int.from_bytes(stream[at:at + 2], "big"))
        at += size
    return tids


def _pipeline_problem(owed: list[bool], bad: list[bool], tids: list[int], closed: bool
                      ) -> str | None:
    """Every frame owed a reply is answered while the connection is open; after a bad header
    the server may close it, but not after dropping a valid frame first."""
    answered = set(tids)
    if not answered <= {1 + i for i, o in enumerate(owed) if o}:
        return f"answers to frames owed none: {sorted(answered)}"
    first_bad = bad.index(True) if True in bad else len(owed)
    owed_tids = [1 + i for i, o in enumerate(owed) if o]
    before = [t for t in owed_tids if t <= first_bad]
    after = [t for t in owed_tids if t > first_bad]
    if not set(before) <= answered:
        return f"frames before the bad header not answered: {sorted(set(before) - answered)}"
    got_after = [t for t in after if t in answered]
    if not closed and got_after != after:
        return f"valid frames dropped on an open connection: {sorted(set(after) - answered)}"
    if closed and got_after != after[:len(got_after)]:
        return "valid frames dropped before the connection was closed"
    return None


@pytest.mark.parametrize("gap_s", [0.0, 0.005], ids=["one write", "frame by frame"])
@pytest.mark.parametrize("bad_kind", list(BAD_MBAP))
def test_a_bad_mbap_header_never_swallows_the_valid_frames_behind_it(bad_kind: str,
                                                                     gap_s: float) -> None:
    """Issue 7 audit: after one MBAP header with length 0 (or protocol id 1) the next 22 of 40
    valid frames got no answer on the still open connection. The server must drop the bad
    frame or close the connection at once (Modbus Messaging on TCP/IP Implementation Guide),
    never lose the frames behind it silently. Well-framed garbage PDUs (owed silence) are mixed
    in: they must not disturb the frames behind them either."""
    rng = random.Random(f"{SEED}-{bad_kind}-{gap_s}")
    start = line_state(_pristine())
    pdus: list[tuple[int, bytes, bool]] = []  # unit, PDU, bad header
    while len(pdus) < 48:
        unit, pdu = next(requests(rng, 1, NODES))
        if pdu and due(start, unit, pdu).kind != "write" and unit != 0:
            pdus.append((unit, pdu, False))
    pdus.insert(6, (1, PROBE, True))
    frames = [_mbap(unit, pdu, 1 + i, **(BAD_MBAP[bad_kind] if is_bad else {}))
              for i, (unit, pdu, is_bad) in enumerate(pdus)]
    owed = [not is_bad and due(start, unit, pdu).kind != "silence"
            for unit, pdu, is_bad in pdus]
    first_bad = next(i for i, (_u, _p, is_bad) in enumerate(pdus) if is_bad)
    with _served("socket", _pristine()) as server:
        got, closed = _stream(server.port, frames, gap_s, expect=sum(owed[:first_bad]))
        probe = _exchange(server.port, [_adu("socket", 1, PROBE, 0xBEEF)], [True])[0]
    problem = _pipeline_problem(owed, [b for _u, _p, b in pdus], _answered_tids(got), closed)
    assert problem is None, f"{bad_kind}: {problem}"
    assert probe[:2] == b"\xbe\xef"  # the server still serves new connections


def test_a_long_pipeline_in_one_write_is_answered_in_full() -> None:
    """Many valid frames in one TCP segment (more than pymodbus's 264-byte receive buffer):
    every one is answered, none is flushed away with the buffer."""
    frames = [_mbap(1, PROBE, 1 + i) for i in range(200)]
    with _served("socket", _pristine()) as server:
        got, closed = _stream(server.port, frames, 0.0, expect=len(frames))
    assert not closed and _answered_tids(got) == list(range(1, 201))
