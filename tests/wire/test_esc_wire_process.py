"""Process B's loop: messages from A applied to the ESCs, mail to A that never blocks, and the
raw socket answering frames on a veth pair (root only; skipped with the reason otherwise).
"""

from __future__ import annotations

import itertools
import multiprocessing
import select
import socket
import time

import pytest
from test_esc import description, make_line, one
from wire_line import veth_pair

from app.ethercat_wire import datagrams as D
from app.ethercat_wire import messages, wire_process
from app.ethercat_wire import registers as R
from app.ethercat_wire.datagrams import Cmd, Request
from app.ethercat_wire.wire_process import Mailman, apply_message, cycle_counts


@pytest.fixture
def pipe():
    a, b = multiprocessing.Pipe()
    yield a, b
    a.close()
    b.close()


def drain(conn) -> list[tuple]:
    got = []
    while conn.poll(0.05):
        got.append(conn.recv())
    return got


def test_outputs_stats_and_cycle_counts_waiting_in_the_mail_are_replaced(pipe):
    a, b = pipe
    mail = Mailman(a)
    mail.post((messages.OUTPUTS, 0, b"\x01"))
    mail.post((messages.AL_CONTROL, 0, 2))
    mail.post((messages.OUTPUTS, 0, b"\x02"))
    mail.post((messages.OUTPUTS, 1, b"\x03"))
    mail.post((messages.CYCLE, {0: 2}))
    mail.post((messages.CYCLE, {0: 3, 1: 1}))
    mail.post((messages.STATS, {"frames": 1}))
    mail.post((messages.STATS, {"frames": 2}))
    mail.flush()
    assert drain(b) == [(messages.OUTPUTS, 0, b"\x02"), (messages.AL_CONTROL, 0, 2),
                        (messages.OUTPUTS, 1, b"\x03"), (messages.CYCLE, {0: 5, 1: 1}),
                        (messages.STATS, {"frames": 2})]


def test_the_mail_never_blocks_on_a_full_pipe(pipe):
    a, b = pipe
    mail = Mailman(a)
    for i in range(100):  # ~400 KB: far more than a pipe holds
        mail.post((messages.MAILBOX, 0, bytes([i]) * 4000))
    start = time.monotonic()
    mail.flush()
    assert time.monotonic() - start < 1.0 and mail.pending  # returned, the rest kept
    received = []
    while mail.pending:
        received += drain(b)
        mail.flush()
    received += drain(b)
    assert [m[2][0] for m in received] == list(range(100))  # in order, none lost


def test_messages_from_a_reach_the_escs():
    line, _, _ = make_line(3)
    assert apply_message(line, (messages.AL_STATUS, 1, 0x14, 0x001A))
    assert line.escs[1].mem[R.AL_STATUS] == 0x14 and line.escs[1].mem[R.AL_STATUS_CODE] == 0x1A
    apply_message(line, (messages.LINK, 2, False))
    assert len(line.visible) == 2
    apply_message(line, (messages.LINK, 0, True))
    assert len(line.visible) == 3
    assert not apply_message(line, (messages.STOP,))
    with pytest.raises(IndexError):
        apply_message(line, (messages.AL_STATUS, 7, 1, 0))


def test_cycle_counts_are_taken_once():
    line, _, _ = make_line(2)
    line.escs[1].exchanges = 4
    assert cycle_counts(line) == {1: 4}
    assert cycle_counts(line) == {}


def test_descriptions_pickle_for_the_spawned_process():
    import pickle

    assert pickle.loads(pickle.dumps(description(1))) == description(1)


def test_line_built_from_descriptions_answers_with_its_sii():
    outbox: list[tuple] = []
    line = wire_process.build_line([description(0), description(1)], outbox)
    one(line, Cmd.APWR, -1, R.STATION_ADDRESS, b"\x02\x10")
    one(line, Cmd.FPWR, 0x1002, R.EEPROM_CONTROL, bytes.fromhex("0001 0a00 0000"))
    assert one(line, Cmd.FPRD, 0x1002, R.EEPROM_DATA, bytes(4)).data == (0x101).to_bytes(4,
                                                                                      "little")


# ---- the socket loop on a veth pair -----------------------------------------------------
@pytest.fixture
def veth():
    with veth_pair("w") as pair:
        yield pair


def answer(sock: socket.socket, timeout_s: float) -> bytes:
    """The next frame that came in (a packet socket also sees its own frames going out)."""
    end = time.monotonic() + timeout_s
    while select.select([sock], [], [], max(0.0, end - time.monotonic()))[0]:
        data, addr = sock.recvfrom(2048)
        if addr[2] != wire_process.PACKET_OUTGOING:
            return data
    raise AssertionError("no answer from the wire process")


def test_the_wire_process_answers_frames_and_reports(veth):
    master_if, slave_if = veth
    ctx = multiprocessing.get_context("spawn")
    a_end, b_end = ctx.Pipe()
    proc = ctx.Process(target=wire_process.run,
                       args=(slave_if, [description(i) for i in range(3)], b_end), daemon=True)
    proc.start()
    try:
        assert a_end.poll(30) and a_end.recv() == (messages.READY, slave_if)
        sock = wire_process.open_socket(master_if)  # this veth's frames only, as B's
        frame = D.build([Request(Cmd.BRD, 0, R.TYPE, b"\0\0", idx=0x5A),
                         Request(Cmd.BWR, 0, R.AL_CONTROL, b"\x02\x00", idx=0x5A)])
        sock.send(frame)
        reply = D.replies(answer(sock, 5))
        assert [(r.cmd, r.idx, r.wkc, r.adp) for r in reply] == [
            (Cmd.BRD, 0x5A, 3, 3), (Cmd.BWR, 0x5A, 3, 3)]
        got = []
        end = time.monotonic() + 20  # B's statistics every 100 ms: generous for a loaded host
        while time.monotonic() < end and not any(m[0] == messages.STATS and m[1]["frames"]
                                                 for m in got):
            if a_end.poll(0.1):
                got.append(a_end.recv())
        assert [m for m in got if m[0] == messages.AL_CONTROL] == [
            (messages.AL_CONTROL, pos, 2) for pos in range(3)]
        a_end.send((messages.LINK, 0, False))  # the master's cable: nothing answers
        # B takes the message between frames: frames (each its own index) until one is not
        # answered; the cable back, frames until one is. B answers in order, so the frame
        # not answered before was dropped, not late.
        probe = (i & 0xFF for i in itertools.count(0x60))
        deadline = time.monotonic() + 20
        while (cut := next(probe)) in _answers(sock, cut, 0.3):
            assert time.monotonic() < deadline, "frames still answered with cable 0 pulled"
        a_end.send((messages.LINK, 0, True))
        seen: set[int] = set()
        while True:
            seen |= _answers(sock, back := next(probe), 1.0)
            if back in seen:
                break
            assert time.monotonic() < deadline + 20, "no answer with cable 0 back"
        assert cut not in seen
        sock.close()
        a_end.send((messages.STOP,))
        proc.join(timeout=5)
        assert proc.exitcode == 0
    finally:
        if proc.is_alive():
            proc.terminate()


def _answers(sock: socket.socket, idx: int, timeout_s: float) -> set[int]:
    """Send a BRD with datagram index ``idx``; the indices of the answers that came until its
    own did or ``timeout_s`` passed."""
    sock.send(D.build([Request(Cmd.BRD, 0, R.TYPE, b"\0\0", idx=idx)]))
    seen: set[int] = set()
    end = time.monotonic() + timeout_s
    while idx not in seen and (left := end - time.monotonic()) > 0:
        try:
            seen.add(D.replies(answer(sock, left))[0].idx)
        except AssertionError:
            break
    return seen


def test_error_counters_read_at_0x0300_are_the_models_and_a_write_clears_them():
    """ET1100 0x0300-0x0313 (docs/ethercat-master.md "Damaged cable"): what A counts is what a
    master reads; a write to 0x0300 clears 0x0300-0x030B at once (0x030C and the lost link
    counters stay) and goes to A, whose model clears the same."""
    line, outbox, _ = make_line(3)
    counters = bytes([5, 0, 0, 2, 0, 0, 0, 0, 0, 7, 0, 0, 9, 0, 0, 0, 1, 3, 0, 0])
    assert apply_message(line, (messages.ESC_ERRORS, 1, counters, 0))  # no wire batch yet
    one(line, Cmd.APWR, -1, R.STATION_ADDRESS, b"\x02\x10")
    assert one(line, Cmd.FPRD, 0x1002, 0x0300, bytes(20)).data == counters
    assert one(line, Cmd.APRD, 0, 0x0300, bytes(20)).data == bytes(20)  # the others: none
    one(line, Cmd.FPWR, 0x1002, 0x0300, b"\0\0")
    after = one(line, Cmd.FPRD, 0x1002, 0x0300, bytes(20)).data
    assert after == bytes(12) + bytes([9, 0, 0, 0, 1, 3, 0, 0])
    assert (messages.ESC_ERRORS_WRITE, 1, 0x0300, 2, 1) in outbox  # the first numbered


def test_the_wire_socket_takes_no_frame_another_interface_received(monkeypatch):
    """packet(7): a packet socket opened for an EtherType receives that type from every
    interface until it is bound to one. B's socket must take none of another NIC's frames
    (another master's on another port of the machine): opened with protocol 0, which receives
    nothing, and bound to its interface with the EtherType. Until session 22 it was opened for
    0x88A4: a frame arriving elsewhere between the two calls was queued and B ran it through
    its ESCs and answered it on its own line."""
    real_socket = socket.socket
    with veth_pair("o") as (_own_master, own), veth_pair("p") as (other_master, other):
        foreign = D.build([Request(Cmd.BRD, 0, R.TYPE, b"\0\0", idx=0x66)])

        def a_frame_arrives_elsewhere_meanwhile(*args: int) -> socket.socket:
            sock = real_socket(*args)
            with real_socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(D.ETHERTYPE)) \
                    as seen, real_socket(socket.AF_PACKET, socket.SOCK_RAW, 0) as sender:
                seen.bind((other, D.ETHERTYPE))
                sender.bind((other_master, 0))
                sender.send(foreign)
                answer(seen, 20)  # arrived on `other`: every socket that takes it has it now
            return sock

        monkeypatch.setattr(wire_process.socket, "socket", a_frame_arrives_elsewhere_meanwhile)
        sock = wire_process.open_socket(own)
        monkeypatch.undo()
        try:
            taken = []
            while select.select([sock], [], [], 0.2)[0]:
                taken.append(sock.recvfrom(2048)[1][0])
            assert taken == []
        finally:
            sock.close()
