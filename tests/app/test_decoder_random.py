"""Any query a trainee types gets one clear answer: readings or a DecodeError, never a traceback.

The queries are built from the pieces the Codes tab reads (hex bytes, codes, names, the log
lines' words, object addresses, state words), shuffled and cut, with a fixed seed so a failure
repeats; each failing query is printed.
"""

from __future__ import annotations

import random

from app.decoder import DecodeError, decode

PIECES = (
    "FF00", "81", "02", "00", "04", "0x8204", "0x", "0X10F3:5", "0x1001:0", "10F3:05", "1001",
    "=", ":", ",", ";", "(", ")", "'", "-", "->", "#", "0x000", "NMT", "nmt", "command", "01",
    "80", "82", "7F", "node", "all", "nodes", "Start", "remote", "Reset", "communication",
    "distributed", "clocks:", "COMPENSATING", "FOO", "NOT_SYNCHRONIZED", "network", "recovery",
    "resync", "events", "the", "status", "change", "of", "slaves", "alarm", "16", "0x10",
    "Hex:", "CoE - Emergency", "heartbeat", "guarding", "85", "rx", "tx", "EMCY", "0x06020000",
    "E1", "37", "flags", "error", "register", "0xFFFFFFFFFFFF", "17", "(0x0011)", "999999",
    "MISSING_NODE_ANSWER", "Pre-operational", "OP", "SlaveStateChange", "slave", "=", "from",
    "to", "8", "2", "ECAT_Resync", "\t", "  ", "Ж", "0x1Z", "--", "::", "0x10F3:", ":5",
)


def _query(rng: random.Random) -> str:
    words = [rng.choice(PIECES) for _ in range(rng.randint(1, 9))]
    text = rng.choice((" ", "", "\t")).join(words)
    if rng.random() < 0.2:  # a copy cut anywhere
        text = text[:rng.randint(0, len(text))]
    return text


def test_random_queries_get_readings_or_one_message() -> None:
    rng = random.Random(20261128)
    for _ in range(4000):
        query = _query(rng)
        try:
            found = decode(query)
        except DecodeError as exc:
            assert str(exc).strip(), query
            continue
        except Exception as exc:  # the test: nothing else escapes
            raise AssertionError(f"{query!r}: {type(exc).__name__}: {exc}") from exc
        assert found, f"{query!r}: no reading and no message"
