"""Diagnosis history 0x10F3 and its message format (seed 002 §2.5.2, Tab. 14-19)."""

from __future__ import annotations

import json

import pytest
from cpx_bench import STI, Bench, tab9

from app.ethercat_wire.faces.cpx import CpxFace
from app.ui.panels.object_dictionary import read_rows, render
from devices.cpx.codes import (
    CPX_TEXT_ID_BASE,
    DIAG_CODE_CPX,
    TEXT_IDS,
    DiagType,
    diag_code,
)
from devices.cpx.history import (
    FIRST_SUB,
    FLAG_ACKNOWLEDGE,
    FLAG_DISABLE_INFO,
    FLAG_EMERGENCY,
    FLAG_OVERWRITE_DISCARD,
    MAX_MESSAGES,
    DiagHistory,
)
from devices.cpx.messages import MESSAGE_BYTES, DiagMessage, channel_param
from devices.events import ValueRead
from devices.od import AbortCode, DataType, SdoAbort

# Tab. 15, as printed.
TAB15 = bytes.fromhex("02 00 00 E1 02 02 02 37 1F C5 9D 61 31 00 00 00 05 00 02 05 00 80")
TAB15_MESSAGE = DiagMessage(0xE100_0002, DiagType.ERROR, 0x3702, 0x31_619D_C51F,
                            ((DataType.UNSIGNED8, 2), (DataType.UNSIGNED8, 0x80)))


def msg(n: int, dtype: DiagType = DiagType.ERROR) -> DiagMessage:
    return DiagMessage(diag_code(DIAG_CODE_CPX, 2), dtype, CPX_TEXT_ID_BASE + 2, n,
                       ((DataType.UNSIGNED8, n % 256),))


def test_tab15_example_encodes_byte_for_byte() -> None:
    """Tab. 15 / Tab. 16: diag code, flags, Text-ID, time stamp, two UNSIGNED8 parameters;
    the BYTE[23] entry (Tab. 14) pads the 22 bytes with a zero."""
    raw = TAB15_MESSAGE.encode()
    assert len(raw) == MESSAGE_BYTES == 23
    assert raw == TAB15 + b"\x00"


def test_tab16_fields_decode() -> None:
    """Tab. 16: CPX error 2 (short circuit) marked E1, 2 parameters, type 2, Text-ID 0x3702,
    module 2, channel 0x80 (output channel 0)."""
    m = DiagMessage.decode(TAB15 + b"\x00")
    assert m == TAB15_MESSAGE
    assert m.diag_code >> 24 == DIAG_CODE_CPX and m.diag_code & 0xFF == 2
    assert m.flags == 0x0202 and m.text_id == 0x3702
    assert channel_param(0, output=True) == 0x80
    assert "Short circuit" in m.text()


@pytest.mark.parametrize("text_id", sorted(TEXT_IDS))
def test_tab17_text_ids(text_id: int) -> None:
    """Tab. 17: the EtherCAT Text-IDs of the ESI file, with their English text."""
    m = DiagMessage(diag_code(0xE8, 0x1000), DiagType.ERROR, text_id, 0)
    assert TEXT_IDS[text_id][1] in m.text()
    assert DiagMessage.decode(m.encode()) == m


def test_sub_layout_and_defaults() -> None:
    """Tab. 14: max 64 messages, flags 0x0000, messages from sub 6."""
    bench = Bench(master=False)
    read = lambda sub: bench.apply("read_object", index=0x10F3, sub=sub)  # noqa: E731
    assert read(1) == MAX_MESSAGES == 64
    assert read(5) == 0x0000
    assert (read(0), read(2), read(3), read(4)) == (5, 0, 0, False)


def test_overwrite_mode_keeps_the_last_64() -> None:
    """Tab. 18 bit 4 = 0: once 64 messages are stored the oldest is overwritten."""
    h = DiagHistory()
    for n in range(MAX_MESSAGES + 5):
        assert h.add(msg(n))
    ordered = h.ordered()
    assert len(ordered) == MAX_MESSAGES
    assert [m.timestamp_ns for _s, m in ordered] == list(range(5, MAX_MESSAGES + 5))
    assert h.newest == FIRST_SUB + 4 and h.sub0 == FIRST_SUB + MAX_MESSAGES - 1
    assert h.flags & FLAG_OVERWRITE_DISCARD


def test_acknowledge_mode_loses_new_messages_when_64_are_unacknowledged() -> None:
    """Tab. 18 bit 4 = 1: with 64 unacknowledged messages new ones are lost."""
    h = DiagHistory(flags=FLAG_ACKNOWLEDGE)
    for n in range(MAX_MESSAGES):
        assert h.add(msg(n))
    assert not h.add(msg(99))
    assert h.lost == 1 and h.flags & FLAG_OVERWRITE_DISCARD
    assert [m.timestamp_ns for _s, m in h.ordered()][-1] == MAX_MESSAGES - 1
    h.write_acknowledged(FIRST_SUB + 9)  # the first ten acknowledged: ten places free
    for n in range(10):
        assert h.add(msg(100 + n))
    assert not h.add(msg(200))
    assert h.unacknowledged() == MAX_MESSAGES


def test_new_message_available_in_both_modes() -> None:
    """Sub 4: Overwrite mode - falls when the newest message is read; Acknowledge mode -
    falls when the newest message is acknowledged."""
    h = DiagHistory()
    h.add(msg(1))
    h.add(msg(2))
    assert h.new_message
    h.read(FIRST_SUB)
    assert h.new_message
    h.read(FIRST_SUB + 1)
    assert not h.new_message
    h = DiagHistory(flags=FLAG_ACKNOWLEDGE)
    h.add(msg(1))
    h.add(msg(2))
    h.read(FIRST_SUB + 1)
    assert h.new_message
    h.write_acknowledged(FIRST_SUB)
    assert h.new_message
    h.write_acknowledged(FIRST_SUB + 1)
    assert not h.new_message


def test_writing_zero_to_sub3_clears() -> None:
    """ETG.1020: 0 in sub 3 clears the history; Acknowledge mode keeps what is not
    acknowledged."""
    h = DiagHistory()
    for n in range(3):
        h.add(msg(n))
    h.write_acknowledged(0)
    assert h.count == 0 and h.newest == 0 and h.sub0 == 5 and not h.new_message
    h = DiagHistory(flags=FLAG_ACKNOWLEDGE)
    for n in range(5):
        h.add(msg(n))
    h.write_acknowledged(FIRST_SUB + 1)
    h.write_acknowledged(0)
    assert [m.timestamp_ns for _s, m in h.ordered()] == [2, 3, 4]
    assert h.newest == FIRST_SUB + 2 and h.new_message


def test_writing_zero_with_none_acknowledged_deletes_nothing_in_acknowledge_mode() -> None:
    """ETG.1020, Acknowledge mode (Tab. 18 bit 4 = 1): 0 in sub 3 deletes the acknowledged
    messages. None acknowledged, none goes: the master has not seen them, which is what the
    mode is for; Overwrite mode deletes them all."""
    h = DiagHistory(flags=FLAG_ACKNOWLEDGE)
    for n in range(3):
        h.add(msg(n))
    h.write_acknowledged(0)
    assert [m.timestamp_ns for _s, m in h.ordered()] == [0, 1, 2]
    assert (h.newest, h.acknowledged, h.sub0, h.new_message) == (FIRST_SUB + 2, 0, 8, True)
    h.write_acknowledged(FIRST_SUB + 2)
    h.write_acknowledged(0)
    assert (h.count, h.newest, h.sub0, h.new_message) == (0, 0, 5, False)


@pytest.mark.parametrize(("value", "code"), [
    (1, AbortCode.VALUE_TOO_LOW), (5, AbortCode.VALUE_TOO_LOW),
    (FIRST_SUB + 3, AbortCode.VALUE_RANGE),
    (FIRST_SUB + MAX_MESSAGES - 1, AbortCode.VALUE_RANGE),
    (FIRST_SUB + MAX_MESSAGES, AbortCode.VALUE_TOO_HIGH), (255, AbortCode.VALUE_TOO_HIGH)])
@pytest.mark.parametrize("flags", [0x0000, FLAG_ACKNOWLEDGE])
def test_acknowledging_a_missing_message_is_refused(value: int, code: AbortCode,
                                                    flags: int) -> None:
    """ETG.1020, sub 3 in both modes: 1 ... 5 (no message sub) 0x06090032 "value too low",
    a message sub holding no message 0x06090030 "value range exceeded", above the last
    message sub (69, choice 5) 0x06090031 "value too high"; nothing changes."""
    h = DiagHistory(flags=flags)
    h.add(msg(0))
    with pytest.raises(SdoAbort) as info:
        h.write_acknowledged(value)
    assert info.value.code is code
    assert (h.acknowledged, h.count, h.new_message) == (0, 1, True)


def test_flags_bits_and_disable_filters() -> None:
    """Sub 5: bits 0 and 4 (Tab. 18, 19) and ETG.1020's disable bits 1-3 are written; bit 5
    is the device's; other bits are refused."""
    h = DiagHistory()
    h.write_flags(FLAG_EMERGENCY | FLAG_ACKNOWLEDGE | FLAG_DISABLE_INFO)
    assert h.emergency_enabled and h.acknowledge_mode
    assert not h.add(msg(1, DiagType.INFO))
    assert h.add(msg(2, DiagType.WARNING))
    with pytest.raises(SdoAbort):
        h.write_flags(0x0100)


def test_reading_past_sub0_is_refused() -> None:
    bench = Bench(master=False)
    with pytest.raises(SdoAbort) as info:
        bench.apply("read_object", index=0x10F3, sub=FIRST_SUB)
    assert info.value.code is AbortCode.NO_SUBINDEX


def test_short_circuit_message_on_the_device_matches_tab15() -> None:
    """§2.5.2: a short circuit at output 0 of module 2 (the CPX-E-8DO of the §2.3.2 system)
    is stored as the Tab. 15 message, with the device's own time stamp (I/O diagnostic
    interface on: §2.5 note)."""
    bench = tab9(**STI).to_op()
    bench.apply("write_object", index=0x7002, sub=1, value=1)
    bench.apply("short_circuit", module=2, channel=0, on=True)
    shorted_at = bench.now
    bench.run(0.01)
    newest = bench.apply("read_object", index=0x10F3, sub=2)
    raw = bench.apply("read_object", index=0x10F3, sub=newest)
    assert raw[:8] == TAB15[:8]  # diag code, flags, Text-ID
    assert raw[16:] == TAB15[16:] + b"\x00"  # parameters: module 2, channel 0x80
    # seen at the next 1 ms cycle; ns since the bus module started (Tab. 16 [4])
    assert DiagMessage.decode(raw).timestamp_ns == (shorted_at + 1000) * 1000
    assert bench.apply("read_object", index=0x10F3, sub=4) is False  # read: newest seen


def test_time_stamps_count_from_the_last_start() -> None:
    """Tab. 16 [4]: «время с момента запуска шинного модуля»: a restart starts the count
    again, DC or not (docs/cpx-e-ec.md choice 45); bit 4 of the flags (ETG.1020's "local
    time stamp") stays clear, as in Tab. 15's «02 02»."""
    bench = tab9(**STI).to_op()
    bench.run(2.0)
    bench.apply("restart")
    restarted_at = bench.now
    bench.run(0.5)
    bench.apply("short_circuit", module=1, on=True)  # the 16DI's sensor supply
    shorted_at = bench.now
    bench.run(0.01)
    message = bench.cpx.history.message(bench.cpx.history.newest)
    assert message is not None and message.text_id == 0x3702
    assert message.timestamp_ns == (shorted_at + 1000 - restarted_at) * 1000
    assert message.encode()[4:6] == bytes((0x02, 0x01))  # one parameter, type 2 (error)


def shorted_tab9() -> tuple[Bench, int, bytes]:
    """The Tab. 15 case (short circuit at output 0 of module 2): bench, newest sub, bytes."""
    bench = tab9(**STI).to_op()
    bench.apply("write_object", index=0x7002, sub=1, value=1)
    bench.apply("short_circuit", module=2, channel=0, on=True)
    bench.run(0.01)
    newest = bench.cpx.history.newest
    message = bench.cpx.history.message(newest)
    assert message is not None and message.text_id == 0x3702
    return bench, newest, message.encode()


def test_message_subs_are_byte23_on_every_read_path() -> None:
    """Tab. 14 / Tab. 27: subs 6 ... are BYTE[23], and Tab. 15 prints a message as its raw
    bytes: the operator's read, the master's CoE upload and the wire's SDO upload all hand
    over the 23 bytes, not their hex text."""
    bench, newest, raw = shorted_tab9()
    entry = bench.cpx.od.entry(0x10F3, newest)
    assert entry.dtype is DataType.OCTET_STRING
    assert entry.bit_length == 8 * MESSAGE_BYTES  # what the SDO information service reports
    assert len(raw) == MESSAGE_BYTES and raw[:8] == TAB15[:8]
    assert bench.apply("read_object", index=0x10F3, sub=newest) == raw
    assert bench.cpx.sdo_upload(0x10F3, newest) == raw
    assert CpxFace().upload_raw(bench.cpx, 0x10F3, newest) == raw


def test_message_shown_in_hex_in_the_objects_tab_and_the_read_event() -> None:
    """A trainee reading 0x10F3:6 in the Objects tab, or a scenario's ``read`` step, sees the
    Tab. 15 bytes in hex; the event record stays JSON."""
    bench, newest, raw = shorted_tab9()
    shown = raw.hex(" ").upper()
    assert shown.startswith("02 00 00 E1 02 02 02 37")
    html = render(read_rows(bench.cpx), f"0x10F3:{newest}")
    assert f"<td>{shown}</td>" in html
    record = ValueRead(0, "cpx", address=f"0x10F3:{newest}", value=raw).to_record()
    assert record["value"] == shown and json.loads(json.dumps(record)) == record


READ_PATHS = {
    "operator": lambda b, sub: b.apply("read_object", index=0x10F3, sub=sub),
    "coe_upload": lambda b, sub: b.cpx.sdo_upload(0x10F3, sub),  # the built-in master's SDO
    "wire": lambda b, sub: CpxFace().upload_raw(b.cpx, 0x10F3, sub),
}


@pytest.mark.parametrize("path", READ_PATHS)
def test_new_message_available_falls_on_every_read_path(path: str) -> None:
    """ETG.1020 (choice 21): in Overwrite mode New Message Available falls when the newest
    message is read, whoever reads it; an older message leaves it up."""
    read = READ_PATHS[path]
    bench, newest, _raw = shorted_tab9()
    assert bench.cpx.od.peek(0x10F3, 4) is True
    older = bench.cpx.history.ordered()[-2][0]
    read(bench, older)
    assert bench.cpx.od.peek(0x10F3, 4) is True
    read(bench, newest)
    assert bench.cpx.od.peek(0x10F3, 4) is False


@pytest.mark.parametrize("path", READ_PATHS)
def test_acknowledge_mode_reads_leave_new_message_available(path: str) -> None:
    """Tab. 18 bit 4 = 1 (Acknowledge): only writing sub 3 lowers it, on any read path."""
    bench = tab9(**STI).to_op()
    bench.apply("write_object", index=0x10F3, sub=5, value=FLAG_ACKNOWLEDGE)
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    newest = bench.cpx.history.newest
    READ_PATHS[path](bench, newest)
    assert bench.cpx.od.peek(0x10F3, 4) is True
    bench.apply("write_object", index=0x10F3, sub=3, value=newest)
    assert bench.cpx.od.peek(0x10F3, 4) is False


@pytest.mark.parametrize("path", READ_PATHS)
def test_reading_past_sub0_is_refused_on_every_path(path: str) -> None:
    """Sub 0 is the highest subindex in use (ETG.1020): above it every read aborts."""
    bench = tab9().to_op()
    with pytest.raises(SdoAbort) as info:
        READ_PATHS[path](bench, bench.cpx.history.sub0 + 1)
    assert info.value.code is AbortCode.NO_SUBINDEX


def test_an_empty_message_slot_shows_no_bytes() -> None:
    """Above sub 0 (ETG.1020: the highest subindex in use) a master's read aborts
    (test_reading_past_sub0_is_refused); the Objects tab shows the slot without bytes."""
    bench = Bench(master=False)
    sub = bench.cpx.history.sub0 + 1
    assert bench.cpx.od.peek(0x10F3, sub) == b""


def test_error_going_is_an_info_message_unless_filtered() -> None:
    """0x2401 "Filter No Error": 0 stores the 'no error' message (CPX error 0), else not."""
    bench = tab9(**STI).to_op()
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    bench.apply("short_circuit", module=1, on=False)
    bench.run(0.01)
    last = bench.cpx.history.ordered()[-1][1]
    assert (last.dtype, last.text_id, last.diag_code) == (DiagType.INFO, 0x3700, 0xE100_0000)
    count = bench.cpx.history.count
    bench.apply("write_object", index=0x2401, sub=0, value=1)
    bench.apply("short_circuit", module=1, on=True)
    bench.run(0.01)
    bench.apply("short_circuit", module=1, on=False)
    bench.run(0.01)
    assert bench.cpx.history.count == count + 1  # the error, not its end


@pytest.mark.parametrize("flags", [FLAG_ACKNOWLEDGE, 0x0000])
def test_acknowledging_an_older_message_takes_back_no_acknowledgement(flags: int) -> None:
    """Tab. 14: sub 3 is the "Newest Acknowledged Message"; ETG.1020: writing a sub
    acknowledges that message and every older one, in both modes (Tab. 18). A master writing
    an older message's sub after a newer one was acknowledged acknowledges nothing new and
    takes no acknowledgement back: sub 3 stays, no message is unacknowledged again, so the
    ring keeps its free places and a later 0 (delete the acknowledged) leaves sub 4 down."""
    h = DiagHistory(flags=flags)
    for n in range(MAX_MESSAGES):
        h.add(msg(n))
    newest = h.newest
    h.read(newest)
    h.write_acknowledged(newest)  # every message seen
    h.write_acknowledged(FIRST_SUB + 9)
    assert (h.acknowledged, h.unacknowledged(), h.new_message) == (newest, 0, False)
    h.write_flags(FLAG_ACKNOWLEDGE)
    h.write_acknowledged(0)
    assert (h.count, h.newest, h.acknowledged, h.new_message) == (0, 0, 0, False)


def test_an_older_acknowledgement_leaves_room_for_new_messages() -> None:
    """Tab. 18 Acknowledge: an acknowledged message may be overwritten by a new one; writing
    an older sub afterwards must not make 60 new messages lost."""
    h = DiagHistory(flags=FLAG_ACKNOWLEDGE)
    for n in range(MAX_MESSAGES):
        h.add(msg(n))
    h.write_acknowledged(h.newest)
    h.write_acknowledged(FIRST_SUB + 3)
    for n in range(MAX_MESSAGES):
        assert h.add(msg(100 + n))
    assert h.lost == 0
    h.write_acknowledged(FIRST_SUB + 3)  # the message there is now new: acknowledged
    assert (h.acknowledged, h.unacknowledged(), h.new_message) == (FIRST_SUB + 3, 60, True)


def test_acknowledging_an_older_message_over_sdo_keeps_sub4_down() -> None:
    """The master's view (0x10F3:3 written, 0x10F3:3 / :4 read) in Acknowledge mode."""
    bench = tab9(**STI).to_op()
    bench.apply("write_object", index=0x10F3, sub=5, value=FLAG_ACKNOWLEDGE)
    for on in (True, False, True):
        bench.apply("short_circuit", module=1, on=on)
        bench.run(0.01)
    newest = bench.apply("read_object", index=0x10F3, sub=2)
    bench.apply("write_object", index=0x10F3, sub=3, value=newest)
    bench.apply("write_object", index=0x10F3, sub=3, value=FIRST_SUB)
    assert bench.apply("read_object", index=0x10F3, sub=3) == newest
    bench.apply("write_object", index=0x10F3, sub=3, value=0)
    assert bench.apply("read_object", index=0x10F3, sub=4) is False
    assert bench.apply("read_object", index=0x10F3, sub=0) == FIRST_SUB - 1


def test_new_message_available_follows_the_mode_in_force() -> None:
    """ETG.1020 sub 4: Overwrite mode TRUE while the newest message is unread, Acknowledge
    mode TRUE while a message is unacknowledged (sub 2 != sub 3). A master switching to
    Acknowledge (Tab. 18 bit 4) after reading, never acknowledging, sees its messages wait;
    acknowledged in Acknowledge mode and back to Overwrite, the newest read or not decides."""
    h = DiagHistory()
    h.add(msg(1))
    h.read(h.newest)
    assert not h.new_message
    h.write_flags(FLAG_ACKNOWLEDGE)
    assert h.new_message  # unacknowledged
    h.write_acknowledged(h.newest)
    assert not h.new_message
    h.add(msg(2))
    h.write_acknowledged(h.newest)  # acknowledged without a read
    h.write_flags(0x0000)
    assert h.new_message  # the newest is unread
    h.read(h.newest)
    assert not h.new_message


def test_overwrite_mode_flags_only_unacknowledged_messages_overwritten() -> None:
    """ETG.1020, sub 5 bit 5 in Overwrite mode (Tab. 18 bit 4 = 0): set when unacknowledged
    messages were overwritten, sub 3 then 0. Messages the master acknowledged may go
    without it: a full ring the master keeps acknowledging never reports a loss."""
    h = DiagHistory()
    for n in range(MAX_MESSAGES):
        h.add(msg(n))
    h.write_acknowledged(h.newest)  # all 64 acknowledged
    for n in range(MAX_MESSAGES - 1):
        h.add(msg(100 + n))  # overwrite the acknowledged ones, sub 3's message kept
    assert (h.acknowledged, h.flags & FLAG_OVERWRITE_DISCARD) == (FIRST_SUB + 63, 0)
    h.add(msg(200))  # sub 3's own message overwritten: none acknowledged is left
    assert (h.acknowledged, h.flags & FLAG_OVERWRITE_DISCARD) == (0, 0)
    h.add(msg(201))  # an unacknowledged message lost
    assert (h.acknowledged, h.flags & FLAG_OVERWRITE_DISCARD) == (0, FLAG_OVERWRITE_DISCARD)
