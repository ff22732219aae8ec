"""Bus timing: frames take the time the bit rate of n1 gives them (seed 004 ch. 4
"Configurazione della rete": n1 = 1..8 -> 10 .. 1000 kBaud, read at power-up), and one line
carries one frame at a time, lowest identifier first.
"""

from __future__ import annotations

import pytest
from canopen_bench import h, make_bench

from devices.canopen.bus_timing import CanFrame, CanLine, bitrate_of_n1, frame_bits, frame_time_us
from devices.servo.parameters import CAN_KBAUD_BY_N1


@pytest.mark.parametrize(("dlc", "rtr", "bits"), [
    (0, False, 55), (1, False, 65), (2, False, 75), (4, False, 95), (8, False, 135),
    (8, True, 55), (1, True, 55),  # a remote frame has no data field
])
def test_frame_bits_worst_case_stuffing(dlc: int, rtr: bool, bits: int) -> None:
    """47 bits of frame + 8 per byte + one stuff bit per four of SOF..CRC."""
    assert frame_bits(dlc, rtr) == bits


@pytest.mark.parametrize(("n1", "kbaud"), sorted(CAN_KBAUD_BY_N1.items()))
def test_bitrate_of_n1(n1: int, kbaud: int) -> None:
    assert bitrate_of_n1(n1) == kbaud * 1000


@pytest.mark.parametrize(("bitrate", "us"), [
    (1_000_000, 135), (800_000, 169), (500_000, 270), (250_000, 540), (125_000, 1080),
    (50_000, 2700), (20_000, 6750), (10_000, 13500),
])
def test_an_sdo_frame_takes(bitrate: int, us: int) -> None:
    assert frame_time_us(8, bitrate) == us


def test_arbitration_lowest_identifier_first_one_at_a_time() -> None:
    line = CanLine(1_000_000)
    for can_id in (0x701, 0x581, 0x181):
        line.offer(CanFrame(can_id, bytes(8), rx=False), 0)
    done = []
    while (frame := line.next_done(10_000)) is not None:
        done.append((frame.can_id, frame.t_us))
    assert done == [(0x181, 135), (0x581, 270), (0x701, 405)]


def test_a_started_frame_is_not_preempted() -> None:
    line = CanLine(125_000)
    line.offer(CanFrame(0x701, bytes(8)), 0)
    assert line.next_done(500) is None  # on the wire until 1080 us
    line.offer(CanFrame(0x080, b""), 500)  # a SYNC arrives meanwhile
    done = []
    while (frame := line.next_done(5_000)) is not None:
        done.append((frame.can_id, frame.t_us))
    assert done == [(0x701, 1080), (0x080, 1080 + frame_time_us(0, 125_000))]


@pytest.mark.parametrize("n1", sorted(CAN_KBAUD_BY_N1))
def test_sdo_round_trip_is_request_plus_answer_on_the_wire(n1: int) -> None:
    """An expedited upload: the request, then the answer, each 8 bytes at n1's bit rate."""
    bench = make_bench(n1=n1)
    offered = bench.t_us
    answer = bench.request(0x601, h("40 18 10 01 00 00 00 00"), 0x581, timeout_ms=200)
    assert answer is not None
    assert answer.t_us - offered == 2 * frame_time_us(8, bitrate_of_n1(n1))


def test_125_kbit_is_visibly_slower_than_1_mbit() -> None:
    """Twenty reads of the statusword, one after the other, in simulated time."""
    def twenty_reads(n1: int) -> int:
        bench = make_bench(n1=n1)
        start = bench.t_us
        for _ in range(20):
            bench.read(0x6041)
        return bench.t_us - start

    slow, fast = twenty_reads(4), twenty_reads(8)
    assert slow >= 2 * fast  # 1 ms steps blur the 8x of the wire, but not to equality
    assert slow >= 20 * 2 * 1080


def test_the_master_frames_keep_their_order_node_frames_compete() -> None:
    """The master's queue is first in, first out (a SYNC sent after an RPDO stays after it);
    between the master's next frame and the node's, the lower identifier wins."""
    line = CanLine(1_000_000)
    line.offer(CanFrame(0x201, bytes(6), rx=True), 0)
    line.offer(CanFrame(0x080, b"", rx=True), 0)
    line.offer(CanFrame(0x181, bytes(2), rx=False), 0)
    line.offer(CanFrame(0x0FF, bytes(2), rx=False), 0)
    order = []
    while (frame := line.next_done(10_000)) is not None:
        order.append(frame.can_id)
    assert order == [0x0FF, 0x181, 0x201, 0x080]
