"""Modbus fuzzing at the pure layer: random and mutated request PDUs at ``serve_line``.

Issue 7 "Hardening": no crash, no hang, each answer a correct response, exception 02 or the
documented silence (seed 004 ch.2 "Eccezioni": only 02 is ever answered), and nothing rejected
changes a drive. The oracle (modbus_oracle.py) works out which of the three is owed from the
rules of docs/modbus.md and the drive's tables: a well-formed request whose addresses all name
something must get the correct reply (read values checked against the drive, written values
found in it), 02 only where an address names nothing, silence only for the documented reasons.
Two drives share the line (nodes 1 and 5, as in tests/app); the simulation advances between
requests so saves finish and the drives move. Sizes: 6,000 requests in CI,
120,000 with ``--full``.
"""

from __future__ import annotations

import random

from fuzz_modbus import judge, line_state, requests
from modbus_oracle import due

from app.modbus.pdu import serve_line
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

SEED = 20240707
REDUCED, FULL = 6_000, 120_000
NODES = (1, 5)
STEP_EVERY = 40  # requests between two simulation advances
BOOT_US = 100_000


def _line() -> list[ServoDrive]:
    drives = [ServoDrive(f"servo{n}", random.Random(n), DriveConfig(node_id=n), MemoryFlash())
              for n in NODES]
    for drive in drives:
        drive.step(BOOT_US)
    return drives


def _advance(drives: list[ServoDrive], rng: random.Random) -> None:
    """A few ms of simulated time; a drive busy saving is stepped until it answers again."""
    t = drives[0].now_us + 1_000 * rng.randint(1, 20)
    for drive in drives:
        drive.step(t)
    while not all(d.responding for d in drives):
        t += 10_000
        for drive in drives:
            drive.step(t)


def test_serve_line_survives_random_and_mutated_requests(full: bool) -> None:
    rng = random.Random(SEED)
    drives = _line()
    counts = {"reply": 0, "exception": 0, "silence": 0}
    owed = {"read": 0, "write": 0, "e02": 0, "silence": 0}
    failures: list[str] = []
    for i, (unit, pdu) in enumerate(requests(rng, FULL if full else REDUCED, NODES)):
        if i % STEP_EVERY == 0:
            _advance(drives, rng)
        before = line_state(drives)
        owed[due(before, unit, pdu).kind] += 1
        outcome = serve_line(drives, unit, pdu)  # any exception fails the test: a crash
        problem = judge(drives, unit, pdu, outcome, before)
        if problem:
            failures.append(f"#{i} unit {unit} {pdu.hex(' ')}: {problem}")
        kind = type(outcome).__name__
        counts[{"Reply": "reply", "Exception02": "exception"}.get(kind, "silence")] += 1
    assert not failures, f"{len(failures)} wrong answers, first: {failures[:5]}"
    # the mix reached every outcome, and the oracle owed reads, writes, 02 and silences
    assert min(counts.values()) > 0.02 * sum(counts.values()), counts
    assert min(owed.values()) > 0.01 * sum(owed.values()), owed
