"""Mailbox transport (SM0 / SM1) and distributed-clock registers of the emulated ESC.

Notes "Mailbox and CoE": a master write covering SM0's last byte delivers a message; the reply
goes to SM1 and sets 0x080D bit 3; a master read covering SM1's last byte clears it; a
repeated mailbox counter (1-7) is a resend and is dropped. DC: SOEM's ecx_configdc() latches
port times with a BWR to 0x0900, reads 0x0918, writes 0x0920 / 0x0928, then spreads 0x0910.
"""

from __future__ import annotations

import struct

from test_esc import addressed, make_line, one, run

from app.ethercat_wire import messages
from app.ethercat_wire import registers as R
from app.ethercat_wire.datagrams import Cmd, Request

SM0_CFG = struct.pack("<HHBBBB", 0x1000, 128, 0x26, 0, 1, 0)
SM1_CFG = struct.pack("<HHBBBB", 0x1080, 128, 0x22, 0, 1, 0)


def mailbox_line(n: int = 1, al_status: int = 0x0002):
    """``n`` addressed slaves with SM0 / SM1 written, in PRE-OP (the mailbox runs from there)
    unless ``al_status`` says otherwise."""
    line, outbox, t = make_line(n)
    addressed(line)
    for i in range(n):
        one(line, Cmd.FPWR, 0x1001 + i, R.SM0, SM0_CFG + SM1_CFG)
        line.escs[i].set_al_status(al_status, 0)
    outbox.clear()
    return line, outbox, t


def request(counter: int, body: bytes = b"\x00\x20\x40\x18\x10\x01\x00\x00\x00\x00") -> bytes:
    """A CoE SDO upload request (0x1018:01) as SOEM writes it: the whole SM0 length."""
    header = struct.pack("<HHBB", len(body), 0, 0, 0x03 | counter << 4)
    return (header + body).ljust(128, b"\0")


def sm1_status(line, station: int = 0x1001) -> int:
    return one(line, Cmd.FPRD, station, R.SM0 + 8 + 5, b"\0").data[0]


def test_write_covering_sm0_last_byte_delivers_the_message():
    line, outbox, _ = mailbox_line()
    one(line, Cmd.FPWR, 0x1001, 0x1000, request(1))
    assert outbox == [(messages.MAILBOX, 0, request(1)[:16])]


def test_in_init_a_write_to_sm0_delivers_nothing():
    """ETG.1000.6: INIT runs no mailbox; the slave stack keeps SM0 / SM1 deactivated from its
    side (PDI control 0x0807 / 0x080F bit 0, SSC DisableSyncManChannel) until INIT -> PREOP
    has checked them. A master that writes SM0 in INIT gets no answer, and nothing reaches the
    model's CoE server. Before, the ESC delivered it and the slave answered in INIT."""
    line, outbox, _ = mailbox_line(al_status=0x0001)
    one(line, Cmd.FPWR, 0x1001, 0x1000, request(1))
    assert outbox == []
    assert one(line, Cmd.FPRD, 0x1001, R.SM0 + 7, b"\0").data[0] & 0x01  # deactivated by PDI
    line.escs[0].queue_mailbox(b"\x0a\x00\x00\x00\x00\x13" + bytes(10))  # a late reply
    assert sm1_status(line) & 0x08 == 0
    line.escs[0].set_al_status(0x0002, 0)  # PRE-OP: the stack starts its mailbox
    assert one(line, Cmd.FPRD, 0x1001, R.SM0 + 7, b"\0").data[0] & 0x01 == 0
    one(line, Cmd.FPWR, 0x1001, 0x1000, request(2))
    assert outbox == [(messages.MAILBOX, 0, request(2)[:16])]


def test_a_repeated_counter_is_dropped():
    line, outbox, _ = mailbox_line()
    for counter in (1, 1, 2):
        one(line, Cmd.FPWR, 0x1001, 0x1000, request(counter))
    assert [m[2][5] >> 4 for m in outbox] == [1, 2]


def test_partial_write_delivers_nothing():
    line, outbox, _ = mailbox_line()
    one(line, Cmd.FPWR, 0x1001, 0x1000, request(1)[:16])
    assert outbox == []


def test_reply_sets_mailbox_full_until_the_master_reads_the_last_byte():
    line, _, _ = mailbox_line()
    assert sm1_status(line) & 0x08 == 0
    line.escs[0].queue_mailbox(b"\x0a\x00\x00\x00\x00\x13" + bytes(10))
    line.escs[0].queue_mailbox(b"\x0a\x00\x00\x00\x00\x23" + bytes(10))
    assert sm1_status(line) & 0x08
    first = one(line, Cmd.FPRD, 0x1001, 0x1080, bytes(128)).data
    assert first[5] == 0x13
    assert sm1_status(line) & 0x08  # the second one was loaded at once
    assert one(line, Cmd.FPRD, 0x1001, 0x1080, bytes(128)).data[5] == 0x23
    assert sm1_status(line) & 0x08 == 0


def test_a_read_short_of_the_last_byte_keeps_the_mailbox_full():
    line, _, _ = mailbox_line()
    line.escs[0].queue_mailbox(b"\x0a\x00\x00\x00\x00\x13" + bytes(10))
    one(line, Cmd.FPRD, 0x1001, 0x1080, bytes(16))
    assert sm1_status(line) & 0x08


def test_repeat_request_puts_the_last_reply_back_and_is_acknowledged():
    """SOEM ecx_mbxreceive: toggles 0x080E bit 1, waits for 0x080F bit 1 to follow."""
    line, _, _ = mailbox_line()
    line.escs[0].queue_mailbox(b"\x0a\x00\x00\x00\x00\x13" + bytes(10))
    one(line, Cmd.FPRD, 0x1001, 0x1080, bytes(128))
    assert sm1_status(line) & 0x08 == 0
    one(line, Cmd.FPWR, 0x1001, R.SM0 + 8 + 5, b"\x00\x03")  # status (ignored) + activate
    assert one(line, Cmd.FPRD, 0x1001, R.SM0 + 8 + 7, b"\0").data[0] & 0x02
    assert sm1_status(line) & 0x08
    assert one(line, Cmd.FPRD, 0x1001, 0x1080, bytes(128)).data[5] == 0x13


def test_replies_wait_for_sm1_and_a_disabled_sm1_drops_them():
    line, _, _ = make_line(1)
    addressed(line)
    line.escs[0].set_al_status(0x0002, 0)  # PRE-OP: the slave has a mailbox
    line.escs[0].queue_mailbox(b"\x0a\x00\x00\x00\x00\x13" + bytes(10))  # no SM1 yet
    one(line, Cmd.FPWR, 0x1001, R.SM0, SM0_CFG + SM1_CFG)
    assert sm1_status(line) & 0x08
    one(line, Cmd.BWR, 0, R.SM0, bytes(32))  # SOEM's reset of all SMs
    one(line, Cmd.FPWR, 0x1001, R.SM0, SM0_CFG + SM1_CFG)
    assert sm1_status(line) & 0x08 == 0


# ---- distributed clocks ------------------------------------------------------------------
def test_receive_time_latch_orders_the_ports_along_the_line():
    line, _, _ = make_line(3)
    addressed(line)
    one(line, Cmd.BWR, 0, R.DC_RECEIVE_TIME_PORT0, bytes(4))
    times = [struct.unpack("<II", one(line, Cmd.FPRD, 0x1001 + i, 0x0900, bytes(8)).data)
             for i in range(3)]
    port0 = [p0 for p0, _ in times]
    assert port0 == sorted(port0) and len(set(port0)) == 3
    # the frame comes back to port 1 later the more slaves follow; the last one has none
    assert times[0][1] - times[0][0] > times[1][1] - times[1][0] > 0 and times[2][1] == 0
    pu = struct.unpack("<Q", one(line, Cmd.FPRD, 0x1001, 0x0918, bytes(8)).data)[0]
    assert pu == port0[0]


def test_system_time_is_local_time_plus_the_offset_the_master_wrote():
    line, _, t = make_line(1)
    addressed(line)
    one(line, Cmd.FPWR, 0x1001, R.DC_SYSTEM_OFFSET, struct.pack("<Q", 10**15))
    t.ns += 5_000
    first = struct.unpack("<Q", one(line, Cmd.FPRD, 0x1001, 0x0910, bytes(8)).data)[0]
    t.ns += 4_000_000
    second = struct.unpack("<Q", one(line, Cmd.FPRD, 0x1001, 0x0910, bytes(8)).data)[0]
    assert first == 10**15 + 5_000 and second - first == 4_000_000


def test_frmw_reference_clock_reads_and_the_others_take_its_time():
    line, _, t = make_line(3)
    addressed(line)
    reply = run(line, Request(Cmd.FRMW, 0x1001, R.DC_SYSTEM_TIME, bytes(8)))[0]
    assert reply.wkc == 3
    assert struct.unpack("<Q", reply.data)[0] == t.ns - 1_000_000  # local time since start


def test_sync0_settings_are_reported_to_process_a():
    line, outbox, _ = make_line(1)
    addressed(line)
    outbox.clear()
    one(line, Cmd.FPWR, 0x1001, R.DC_START_TIME0, struct.pack("<Q", 123_000_000))
    one(line, Cmd.FPWR, 0x1001, R.DC_CYCLE0, struct.pack("<I", 4_000_000))
    one(line, Cmd.FPWR, 0x1001, R.DC_ACTIVATION, b"\x03")
    assert outbox[-1] == (messages.DC, 0, {"activation": 3, "sync0_cycle_ns": 4_000_000,
                                           "start_time_ns": 123_000_000})


def test_a_slave_without_dc_ignores_the_dc_registers():
    line, outbox, _ = make_line(1, dc=False)
    addressed(line)
    outbox.clear()
    one(line, Cmd.FPWR, 0x1001, R.DC_ACTIVATION, b"\x03")
    assert outbox == []


def test_armw_spreads_the_reference_time_and_0x092c_shows_the_difference():
    """ARMW on 0x0910: slave 0 reads, the others take the time; a slave whose own system time
    is 500 ns behind shows 0x092C = 500 with bit 31 set (received time ahead of the local)."""
    line, _, _t = make_line(3)
    addressed(line)
    one(line, Cmd.FPWR, 0x1002, R.DC_SYSTEM_OFFSET, struct.pack("<q", -500))
    reply = run(line, Request(Cmd.ARMW, 0, R.DC_SYSTEM_TIME, bytes(8)))[0]
    assert reply.wkc == 3 and reply.adp == 3
    diff = struct.unpack("<I", one(line, Cmd.FPRD, 0x1002, R.DC_SYSTEM_DIFF, bytes(4)).data)[0]
    assert diff == 0x80000000 | 500
    same = struct.unpack("<I", one(line, Cmd.FPRD, 0x1003, R.DC_SYSTEM_DIFF, bytes(4)).data)[0]
    assert same == 0


def test_a_slave_going_to_init_drops_what_sm1_holds():
    """The slave stack stops its mailbox on every transition to INIT (ETG.1000.6; SSC
    MBX_StopMailboxHandler disables SM1 and frees the send queue): replies and emergencies the
    master has not read are lost, even when the master writes the same SM config again (SOEM
    ecx_reconfig_slave). Staying in a state with a mailbox keeps them."""
    line, _, _ = mailbox_line()
    esc = line.escs[0]
    esc.set_al_status(0x0004, 0)  # SAFEOP
    esc.queue_mailbox(b"\x0a\x00\x00\x00\x00\x13" + bytes(10))
    esc.queue_mailbox(b"\x0a\x00\x00\x00\x00\x23" + bytes(10))
    esc.set_al_status(0x0014, 0x001B)  # still SAFEOP, error flag: nothing goes
    assert sm1_status(line) & 0x08
    esc.set_al_status(0x0001, 0)  # INIT
    assert sm1_status(line) & 0x08 == 0
    one(line, Cmd.FPWR, 0x1001, R.SM0, SM0_CFG + SM1_CFG)
    esc.set_al_status(0x0002, 0)
    assert sm1_status(line) & 0x08 == 0
    esc.queue_mailbox(b"\x0a\x00\x00\x00\x00\x33" + bytes(10))
    assert one(line, Cmd.FPRD, 0x1001, 0x1080, bytes(128)).data[5] == 0x33
