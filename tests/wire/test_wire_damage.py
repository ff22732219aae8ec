"""A damaged cable on the wire: process B spoils the wire master's frames as the built-in master's
(devices/master/esc_errors.py ``run_frame``: the same share per crossing, one draw per crossing
in the same order, a generator seeded as the model says) and the ESC error counters count them
as in embedded mode; the counts reach the model (``esc_counts``) and come back with the model's
own (``esc_errors`` + the last batch applied), so a master reads each count once.
docs/ethercat-wire.md "Damaged cable"; docs/ethercat-master.md "Damaged cable".
"""

from __future__ import annotations

import itertools
import multiprocessing
import random
import select
import socket
import time
from collections.abc import Iterator

import pytest
from test_bridge import WAIT_S, bridged, master_view, sim, wait_for
from test_esc import description, make_line, one
from test_esc_wire_process import answer
from test_faces import line_rig
from wire_line import veth_pair

from app.ethercat_wire import datagrams as D
from app.ethercat_wire import messages, wire_process
from app.ethercat_wire import registers as R
from app.ethercat_wire.datagrams import Cmd, Request
from app.ethercat_wire.esc import Line
from app.ethercat_wire.wire_process import Stats, apply_message
from app.player import reset_in_place
from devices.master.esc_errors import EscErrors, frame_seed, run_frame

IN, OUT = 0, 1
SEED = 1234
RUN = 0  # the rig's loads (messages.DAMAGE)
DEADLINE_S = 20.0  # generous: a loaded shared host (load 7-9 on 2 cores) stalls B and A


def frame(idx: int = 0x11) -> bytearray:
    return D.build([Request(Cmd.BRD, 0, R.TYPE, b"\0\0", idx=idx)])


def counters(line: Line, pos: int) -> bytes:
    """0x0300-0x0313 of the slave at ``pos`` as a master reads them (the line healthy)."""
    return one(line, Cmd.APRD, -pos, R.ERROR_COUNTERS, bytes(20)).data


def damage(line: Line, shares: dict[int, float]) -> None:
    assert apply_message(line, (messages.DAMAGE, shares, SEED, RUN))


def test_a_damaged_cable_spoils_the_frames_as_the_built_in_master_does():
    """Cable 2 spoils half of its crossings: the frames B drops are those run_frame spoils
    with the same generator, and every slave's counters are run_frame's."""
    line, _, _ = make_line(4)
    damage(line, {2: 0.5})
    answered = [line.process(frame()) for _ in range(200)]
    ref, rng = [EscErrors() for _ in range(4)], random.Random(SEED)
    spoiled = [run_frame(ref, 3, {2: 0.5}, rng) for _ in range(200)]
    assert answered == [not s for s in spoiled]
    assert 50 < sum(spoiled) < 200 and line.spoiled == sum(spoiled)
    assert line.frames == 200 - sum(spoiled)  # a spoiled frame is not answered, as lost
    damage(line, {})  # repaired: the counters stay
    assert [counters(line, p) for p in range(4)] == [e.registers() for e in ref]
    assert ref[2].invalid[IN] > 0 and ref[1].invalid[OUT] > 0 and ref[0].forwarded[OUT] > 0


def test_an_undamaged_line_loses_nothing_and_counts_nothing():
    line, _, _ = make_line(3)
    damage(line, {})
    assert all(line.process(frame()) for _ in range(100))
    assert line.spoiled == 0 and [counters(line, p) for p in range(3)] == [bytes(20)] * 3
    assert line.take_esc_counts() is None


def test_a_damaged_cable_behind_a_cut_is_not_crossed():
    """Cable 2 damaged, cable 1 pulled: the frames turn back at slave 0, as the built-in
    master's reach the last slave they get to."""
    line, _, _ = make_line(3)
    apply_message(line, (messages.LINK, 1, False))
    damage(line, {2: 1.0})
    assert all(line.process(frame()) for _ in range(20))
    damage(line, {0: 1.0})
    assert not line.process(frame())


def test_counts_go_to_the_model_once_and_its_answer_does_not_count_them_twice():
    line, _, _ = make_line(2)
    damage(line, {1: 1.0})
    for _ in range(3):
        assert not line.process(frame())
    seq, counts = line.take_esc_counts()
    assert set(counts) == {0, 1}
    assert EscErrors.from_registers(counts[1]).invalid[IN] == 3
    assert EscErrors.from_registers(counts[0]).forwarded[OUT] == 3
    assert line.take_esc_counts() is None  # taken once
    for _ in range(2):
        line.process(frame())
    model = EscErrors(lost_link=[1, 0, 0, 0])  # a lost link the model counted meanwhile
    # sent before the model had the batch: the batch still shows on top of it
    apply_message(line, (messages.ESC_ERRORS, 1, model.registers(), seq - 1))
    shown = EscErrors.from_registers(line.escs[1].counters.registers())
    assert shown.invalid[IN] == 5 and shown.lost_link[IN] == 1
    model.add(EscErrors.from_registers(counts[1]))  # the model with the batch added
    apply_message(line, (messages.ESC_ERRORS, 1, model.registers(), seq))
    damage(line, {})
    shown = EscErrors.from_registers(counters(line, 1))
    assert shown.invalid[IN] == 5 and shown.lost_link[IN] == 1


def test_a_masters_write_clears_what_the_model_has_not_taken_yet():
    line, outbox, _ = make_line(2)
    damage(line, {1: 1.0})
    line.process(frame())
    line.take_esc_counts()  # sent to A, not yet answered
    line.process(frame())
    damage(line, {})
    one(line, Cmd.APWR, -1, 0x0300, b"\0\0")  # clears 0x0300-0x030B
    shown = EscErrors.from_registers(counters(line, 1))
    assert shown.invalid == [0] * 4 and shown.epu == 2
    assert (messages.ESC_ERRORS_WRITE, 1, 0x0300, 2, 2) in outbox  # after batch 1


def test_the_models_answer_to_a_batch_before_a_masters_write_does_not_bring_back_the_cleared():
    """B sends batch k; the master clears the counters; A, which has not seen the write yet,
    adds batch k and answers at once (tagged k). The write is numbered after batch k, in the
    same sequence, so B clears the model's copy again until A's answer to the write (tagged
    with its number) comes: a cleared count does not come back, a count after the write shows
    once (docs/ethercat-wire.md "Damaged cable")."""
    line, outbox, _ = make_line(2)
    damage(line, {1: 1.0})
    for _ in range(5):
        line.process(frame())
    seq, counts = line.take_esc_counts()  # B -> A: batch k
    damage(line, {})
    one(line, Cmd.APWR, -1, R.ERROR_COUNTERS, bytes(20))  # the master clears slave 1
    write = outbox[-1]  # B -> A: esc_errors_write
    damage(line, {1: 1.0})
    line.process(frame())  # counted after the write
    damage(line, {})
    model = EscErrors()  # A adds batch k and answers before it handles the write
    model.add(EscErrors.from_registers(counts[1]))
    apply_message(line, (messages.ESC_ERRORS, 1, model.registers(), seq))
    shown = EscErrors.from_registers(counters(line, 1))
    assert shown.invalid[IN] == 1 and shown.epu == 1
    assert write[:4] == (messages.ESC_ERRORS_WRITE, 1, R.ERROR_COUNTERS, 20) and write[4] > seq
    model.write(R.ERROR_COUNTERS, 20)  # A handles the write and answers with its number
    apply_message(line, (messages.ESC_ERRORS, 1, model.registers(), write[4]))
    shown = EscErrors.from_registers(counters(line, 1))
    assert shown.invalid[IN] == 1 and shown.epu == 1
    assert line.escs[1].counters.writes == []  # acknowledged: not applied again


def test_batches_and_writes_share_one_sequence_in_the_order_b_sends_them():
    line, outbox, _ = make_line(2)
    damage(line, {1: 1.0})
    line.process(frame())
    first, _ = line.take_esc_counts()
    damage(line, {})
    one(line, Cmd.APWR, 0, 0x0310, b"\0")
    one(line, Cmd.APWR, -1, 0x030C, b"\0")
    damage(line, {1: 1.0})
    line.process(frame())
    last, _ = line.take_esc_counts()
    writes = [m[4] for m in outbox if m[0] == messages.ESC_ERRORS_WRITE]
    assert [first, *writes, last] == [first, first + 1, first + 2, first + 3]


def test_statistics_count_the_spoiled_frames_as_lost():
    line, _, _ = make_line(2)
    damage(line, {0: 1.0})
    line.process(frame())
    assert Stats().report(line)["lost_frames"] == 1


def test_a_new_run_restarts_the_crossings_and_drops_the_old_runs_counts():
    """A scenario load (a new run: the same seed may come again) restarts B's crossings; what
    the old run counted and A has not taken (a batch on its way, the count not sent) and the
    statistics of the old run are dropped: the fresh model's counters are the ESC's."""
    line, _, _ = make_line(2)
    damage(line, {1: 1.0})
    for _ in range(3):
        line.process(frame())
    line.take_esc_counts()  # on its way to A
    line.process(frame())  # not sent yet
    assert apply_message(line, (messages.DAMAGE, {}, SEED, 1))
    assert Stats().report(line)["lost_frames"] == 0 and line.frames == 0
    assert counters(line, 1) == bytes(20)
    assert apply_message(line, (messages.DAMAGE, {1: 0.5}, SEED, 1))
    answered = [line.process(frame()) for _ in range(50)]
    ref, rng = [EscErrors() for _ in range(2)], random.Random(SEED)
    assert answered == [not run_frame(ref, 1, {1: 0.5}, rng) for _ in range(50)]


def test_the_seed_is_drawn_from_a_copy_of_the_masters_generator():
    """The wire's generator follows the rig's seed without taking a draw from the master's
    (its DC measurement keeps its own sequence)."""
    rng = random.Random(8)
    state = rng.getstate()
    assert frame_seed(rng) == frame_seed(random.Random(8)) != frame_seed(random.Random(9))
    assert rng.getstate() == state


# ---- process A: the model's damage reaches B, B's counts reach the model ------------------
@pytest.fixture
def wire():
    with bridged(line_rig("OP")) as wired:
        yield wired


def test_the_models_damage_reaches_b_and_b_s_counts_reach_the_model(wire):
    runtime, _bridge, b = wire
    first = b.expect(lambda m: m[0] == messages.DAMAGE)
    seed = first[2]  # frame_seed of the master's generator as the bridge attached
    assert first == (messages.DAMAGE, {}, seed, 0) and isinstance(seed, int)
    runtime.command("master", "damage_cable", {"cable": 2, "percent": 30}).result(WAIT_S)
    b.expect(lambda m: m == (messages.DAMAGE, {2: 0.3}, seed, 0))
    counted = EscErrors(invalid=[4, 0, 0, 0], epu=4)
    b.send(messages.ESC_COUNTS, 1, {2: counted.registers()}, 0)
    b.expect(lambda m: m == (messages.ESC_ERRORS, 2, counted.registers(), 1))
    assert sim(runtime, lambda: master_view(runtime).links[2].esc.snapshot()) == \
        counted.snapshot()
    b.send(messages.STATS, {"frames": 10, "lrw": 10, "cycle_us": 4000.0, "wkc_errors": 0,
                            "lost_frames": 4, "run": 0})
    wait_for(lambda: sim(runtime, lambda: master_view(runtime).lost_frames) == 4)
    runtime.command("master", "repair_cable", {"cable": 2}).result(WAIT_S)
    b.expect(lambda m: m == (messages.DAMAGE, {}, seed, 0))


def test_a_scenario_load_puts_the_master_in_external_mode_again_and_b_in_the_new_run(wire):
    """A load resets the rig in place (the same master object, its fresh state not external):
    the bridge attaches again, so the built-in master does not drive the line next to the
    wire master (a damaged cable would be counted twice), and B gets the new run (damage and
    seed sent again, even when the same). The old run's counts on their way are dropped."""
    runtime, _bridge, b = wire
    first = b.expect(lambda m: m[0] == messages.DAMAGE)
    runtime.command("master", "damage_cable", {"cable": 2, "percent": 100}).result(WAIT_S)
    b.expect(lambda m: m[0] == messages.DAMAGE and m[1] == {2: 1.0})
    sim(runtime, lambda: reset_in_place(runtime.rig, line_rig("OP")))
    new = b.expect(lambda m: m[0] == messages.DAMAGE and m[1] == {})
    assert sim(runtime, lambda: master_view(runtime).external) is True
    assert new[3] == first[3] + 1  # a new run (its seed from the fresh master's generator)
    runtime.command("master", "damage_cable", {"cable": 2, "percent": 100}).result(WAIT_S)
    b.expect(lambda m: m == (messages.DAMAGE, {2: 1.0}, new[2], new[3]))
    start = sim(runtime, lambda: runtime.rig.clock.now_us)
    wait_for(lambda: sim(runtime, lambda: runtime.rig.clock.now_us) > start + 100_000)
    master = master_view(runtime)  # only B's frames cross the cable: nothing counted here
    assert sim(runtime, lambda: [link.esc.registers() for link in master.links]) == \
        [bytes(20)] * 4
    assert sim(runtime, lambda: master.lost_frames) == 0
    old = EscErrors(invalid=[9, 0, 0, 0], epu=9)
    b.send(messages.ESC_COUNTS, 1, {2: old.registers()}, first[3])  # the old run's
    counted = EscErrors(invalid=[1, 0, 0, 0], epu=1)
    b.send(messages.ESC_COUNTS, 2, {2: counted.registers()}, new[3])
    b.expect(lambda m: m == (messages.ESC_ERRORS, 2, counted.registers(), 2))
    assert sim(runtime, lambda: master.links[2].esc.registers()) == counted.registers()


# ---- process B on a veth pair: frames from the master's side ------------------------------
@pytest.fixture
def veth():
    with veth_pair("k") as pair:
        yield pair


def test_the_wire_process_drops_what_a_damaged_cable_spoils(veth):
    """Each frame carries its own index, so an answer is matched to its frame: on a loaded
    machine an answer may come after the next frame went out. B has the damage once it sends
    counts of spoiled frames (A's message may wait behind frames), not after some time."""
    master_if, slave_if = veth
    ctx = multiprocessing.get_context("spawn")
    a_end, b_end = ctx.Pipe()
    proc = ctx.Process(target=wire_process.run,
                       args=(slave_if, [description(i) for i in range(3)], b_end), daemon=True)
    proc.start()
    sock = None
    try:
        assert a_end.poll(30) and a_end.recv() == (messages.READY, slave_if)
        # B's own socket: bound before it receives, so no other test's frames (another veth)
        sock = wire_process.open_socket(master_if)
        sent, seen = (i & 0xFF for i in itertools.count(0x20)), set()
        for _ in range(5):  # undamaged: every frame answered
            assert _answered(sock, next(sent), 5, seen) == 3
        a_end.send((messages.DAMAGE, {1: 1.0}, SEED, RUN))
        counts = _spoiled_counts(sock, a_end, sent)
        assert EscErrors.from_registers(counts[1]).invalid[IN] >= 1
        assert EscErrors.from_registers(counts[0]).forwarded[OUT] >= 1
        dropped = next(sent)
        seen.clear()
        assert _answered(sock, dropped, 0.5, seen) is None
        a_end.send((messages.DAMAGE, {}, SEED, RUN))
        deadline = time.monotonic() + DEADLINE_S
        while (wkc := _answered(sock, next(sent), 1, seen)) is None:
            assert time.monotonic() < deadline, "no answer after the repair"
        assert wkc == 3
        # B answers in order: the answer after the repair came, so the one dropped never will
        assert dropped not in seen
        a_end.send((messages.STOP,))
        proc.join(timeout=5)
    finally:
        if sock is not None:
            sock.close()
        if proc.is_alive():
            proc.terminate()


def _answered(sock: socket.socket, idx: int, timeout_s: float, seen: set[int]) -> int | None:
    """Send a frame with datagram index ``idx``; its answer's working counter, or None when
    none came within ``timeout_s``. The indices of answers to earlier frames go to ``seen``."""
    sock.send(frame(idx))
    end = time.monotonic() + timeout_s
    while (left := end - time.monotonic()) > 0:
        try:
            reply = D.replies(answer(sock, left))[0]
        except AssertionError:
            return None
        if reply.idx == idx:
            return reply.wkc
        seen.add(reply.idx)
    return None


def _spoiled_counts(sock: socket.socket, conn, sent: Iterator[int]) -> dict[int, bytes]:
    """Frames sent until B's first batch of ESC counts (every 10 ms while it counts): the
    sign that the damage reached B and spoiled frames, whatever the machine's load. Answers
    to the frames B had before the damage are read and dropped on the way."""
    deadline = time.monotonic() + DEADLINE_S
    while time.monotonic() < deadline:
        sock.send(frame(next(sent)))
        while select.select([sock], [], [], 0)[0]:
            sock.recv(2048)
        while conn.poll(0.02):
            m = conn.recv()
            if m[0] == messages.ESC_COUNTS:
                return m[2]
    raise AssertionError("no esc_counts from B")
