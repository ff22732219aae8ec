"""The TRS-CAT's 0x10F3 sub 3 / 4 / 5 rules where seed 001 §9.3.7 is silent: ETG.1020's, as for
the CPX-E-EC (docs/cpx-e-ec.md choice 21; docs/trscat.md "0x10F3"). §9.3.7 fixes the mode:
acknowledge ("in modalità acknowledge"), 20 messages."""

from __future__ import annotations

from devices.trscat.diagnostics import (
    FIRST_MESSAGE_SUB,
    MAX_MESSAGES,
    DiagHistory,
    DiagMessage,
    DiagType,
)


def _msg(n: int) -> DiagMessage:
    return DiagMessage(0xE8003220, DiagType.ERROR, 0x3220, n, (n,), f"m{n}")


def _full(extra: int = 0) -> DiagHistory:
    hist = DiagHistory()
    for n in range(MAX_MESSAGES + extra):
        hist.add(_msg(n))
    return hist


def test_writing_zero_deletes_only_the_acknowledged_messages() -> None:
    """ETG.1020, acknowledge mode: sub 3 = 0 deletes "all acknowledged messages". The ones the
    master has not acknowledged stay where they are; sub 3 reads 0, sub 4 stays TRUE."""
    hist = DiagHistory()
    for n in range(3):
        hist.add(_msg(n))  # subs 6, 7, 8
    hist.acknowledge(7)
    hist.acknowledge(0)
    assert sorted(hist.messages) == [8] and hist.messages[8].params == (2,)
    assert (hist.newest, hist.newest_ack, hist.new_available) == (8, 0, True)
    hist.acknowledge(0)  # none acknowledged: nothing goes
    assert sorted(hist.messages) == [8]
    assert hist.add(_msg(3)) and hist.newest == 9  # the ring goes on after sub 8
    hist.acknowledge(9)
    hist.acknowledge(0)
    assert (hist.messages, hist.newest, hist.newest_ack, hist.new_available) == \
        ({}, 0, 0, False)


def test_a_kept_message_is_acknowledged_and_deleted_later() -> None:
    """Twenty unacknowledged messages survive a 0; acknowledged afterwards, they go."""
    hist = _full()
    hist.acknowledge(0)
    assert len(hist.messages) == MAX_MESSAGES and hist.new_available
    hist.acknowledge(FIRST_MESSAGE_SUB + 4)  # the five oldest
    hist.acknowledge(0)
    assert sorted(hist.messages) == list(range(FIRST_MESSAGE_SUB + 5, 26))
    assert hist.add(_msg(99)) and hist.newest == FIRST_MESSAGE_SUB  # a free place
