"""The TRS-CAT's 0x10F3 sub 3 / 4 / 5 rules where seed 001 §9.3.7 is silent: ETG.1020's, as for
the CPX-E-EC (docs/cpx-e-ec.md choice 21; docs/trscat.md "0x10F3"). §9.3.7 fixes the mode:
acknowledge ("in modalità acknowledge"), 20 messages."""

from __future__ import annotations

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.od import AbortCode, SdoAbort
from devices.trscat.diagnostics import (
    FIRST_MESSAGE_SUB,
    FLAG_OVERWRITE_DISCARD,
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


@pytest.mark.parametrize(("value", "code"), [
    (1, AbortCode.VALUE_TOO_LOW), (5, AbortCode.VALUE_TOO_LOW),
    (9, AbortCode.VALUE_RANGE), (25, AbortCode.VALUE_RANGE),
    (26, AbortCode.VALUE_TOO_HIGH), (255, AbortCode.VALUE_TOO_HIGH)],
    ids=lambda v: str(v) if isinstance(v, int) and not isinstance(v, AbortCode) else v.name)
def test_sub3_naming_no_message_is_refused_with_etg1020s_code(value: int,
                                                               code: AbortCode) -> None:
    """ETG.1020: 1..5 "value too low" 0x06090032, a message sub holding no message "value
    range exceeded" 0x06090030, past the last message sub (25 here) "value too high"
    0x06090031. Nothing changes."""
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    bench.apply("inject_fault", module=1, fault="AN_PLUS_12V")
    bench.apply("inject_fault", module=1, fault="AN_MINUS_12V")
    bench.run(0.002)
    bench.write(0x10F3, 3, 6)
    with pytest.raises(SdoAbort) as info:
        bench.write(0x10F3, 3, value)
    assert info.value.code is code
    assert [bench.read(0x10F3, s) for s in (2, 3, 4)] == [7, 6, True]


def test_overwriting_the_message_sub3_names_sets_sub3_to_zero() -> None:
    """ETG.1020: sub 3 names an acknowledged message; once a new message takes its place it
    names none, and reads 0. Else sub 3 = sub 2 (all acknowledged, to a master) while twenty
    messages wait and sub 4 (0x1AFF:5) is TRUE."""
    hist = _full()
    hist.acknowledge(FIRST_MESSAGE_SUB)  # the oldest only
    assert hist.add(_msg(99)) and hist.newest == FIRST_MESSAGE_SUB
    assert (hist.newest_ack, hist.new_available) == (0, True)
    hist.acknowledge(0)  # none acknowledged now: nothing goes
    assert len(hist.messages) == MAX_MESSAGES
    hist.acknowledge(FIRST_MESSAGE_SUB)
    assert (hist.newest_ack, hist.new_available) == (FIRST_MESSAGE_SUB, False)


def test_a_discarded_message_sets_flags_bit5() -> None:
    """ETG.1020 sub 5 bit 5 in acknowledge mode, set by the device: a new message was
    discarded, twenty unacknowledged ones in the way. A flags write keeps it; a write of
    sub 3 (an acknowledgement or 0) takes it away."""
    hist = _full(extra=1)
    assert (hist.lost, hist.flags) == (1, FLAG_OVERWRITE_DISCARD)
    hist.set_flags(0x0001 | FLAG_OVERWRITE_DISCARD)
    assert hist.flags == 0x0001 | FLAG_OVERWRITE_DISCARD
    hist.set_flags(0x0000)
    assert hist.flags == FLAG_OVERWRITE_DISCARD  # the device's bit, not the master's
    hist.acknowledge(hist.newest)
    assert hist.flags == 0
    assert hist.add(_msg(100))  # an acknowledged one overwritten: no loss
    assert hist.flags == 0
    for n in range(MAX_MESSAGES):
        hist.add(_msg(200 + n))
    assert hist.flags == FLAG_OVERWRITE_DISCARD
    hist.acknowledge(0)  # deletes nothing (none acknowledged), the bit goes
    assert hist.flags == 0


def test_bit5_in_the_object_dictionary() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    for n in range(MAX_MESSAGES + 1):
        bench.trs.diag.add(_msg(n))
    assert bench.read(0x10F3, 5) == FLAG_OVERWRITE_DISCARD
    bench.write(0x10F3, 5, 0x0001)
    assert bench.read(0x10F3, 5) == 0x0001 | FLAG_OVERWRITE_DISCARD
    bench.apply("acknowledge_messages")
    assert bench.read(0x10F3, 5) == 0x0001
