"""The emulated ESC line against byte-level frames: addressing, working counters, registers.

Facts checked are those of /work/shared/docs/ethercat-wire-notes.md ("Frames and datagrams",
"Registers touched") and ETG.1000.4 §5.4 (WKC: read +1, write +1, read-write +3; LRW +1 for a
read FMMU, +2 for a write FMMU).
"""

from __future__ import annotations

import contextlib
import struct

import pytest

from app.ethercat_wire import datagrams as D
from app.ethercat_wire import messages, sii
from app.ethercat_wire import registers as R
from app.ethercat_wire.datagrams import Cmd, Request
from app.ethercat_wire.dc import DcClock
from app.ethercat_wire.description import Pdo, PdoEntry, SlaveDescription, SyncManager
from app.ethercat_wire.esc import Esc, Line


def description(i: int = 0, dc: bool = True) -> SlaveDescription:
    return SlaveDescription(
        device_id=f"s{i}", name=f"Slave {i}", vendor_id=0xABC, product_code=0x100 + i,
        revision=0x0002_0001, serial=i, group="Test", order_code=f"T-{i}",
        mailbox=(0x1000, 128, 0x1080, 128), coe_details=0x01,
        sync_managers=(SyncManager(0x1000, 128, 0x26, 1), SyncManager(0x1080, 128, 0x22, 1),
                       SyncManager(0x1100, 2, 0x64, 1), SyncManager(0x1180, 4, 0x20, 1)),
        rx_pdos=(Pdo(0x1600, "Out", (PdoEntry(0x7000, 1, 16, "Word out"),)),),
        tx_pdos=(Pdo(0x1A00, "In", (PdoEntry(0x6000, 1, 32, "Dword in"),)),),
        dc_supported=dc)


class FakeTime:
    def __init__(self) -> None:
        self.ns = 1_000_000

    def __call__(self) -> int:
        return self.ns


def make_line(n: int = 3, dc: bool = True) -> tuple[Line, list[tuple], FakeTime]:
    outbox: list[tuple] = []
    t = FakeTime()
    clock = DcClock(t)
    escs = [Esc(i, description(i, dc), sii.build(description(i, dc)), clock, outbox)
            for i in range(n)]
    return Line(escs, outbox), outbox, t


def run(line: Line, *requests: Request) -> list[D.Reply]:
    frame = D.build(list(requests))
    assert line.process(frame)
    return D.replies(frame)


def one(line: Line, cmd: int, adp: int, ado: int, data: bytes) -> D.Reply:
    return run(line, Request(cmd, adp, ado, data))[0]


def addressed(line: Line) -> None:
    for i in range(len(line.escs)):
        one(line, Cmd.APWR, -i, R.STATION_ADDRESS, struct.pack("<H", 0x1001 + i))


# ---- frames -------------------------------------------------------------------------------
def test_frame_roundtrip_keeps_index_length_and_chains_with_the_more_bit():
    frame = D.build([Request(Cmd.BRD, 0, 0, b"\0\0", idx=7), Request(Cmd.NOP, 0, 0, b"xy", idx=8)])
    dgs = D.parse(frame)
    assert [(d.cmd, d.idx, d.more, d.length) for d in dgs] == [
        (Cmd.BRD, 7, True, 2), (Cmd.NOP, 8, False, 2)]
    assert len(frame) == D.MIN_FRAME
    line, _, _ = make_line(2)
    before = len(frame)
    line.process(frame)
    assert len(frame) == before and [r.idx for r in D.replies(frame)] == [7, 8]


def test_truncated_frame_is_rejected():
    frame = D.build([Request(Cmd.BRD, 0, 0, b"\0" * 8)])
    frame[14] = 0xFF  # EtherCAT length larger than the frame
    frame[15] = 0x17
    with pytest.raises(D.FrameError):
        D.parse(frame[:30])


# ---- addressing and working counters ----------------------------------------------------
def test_brd_counts_every_slave_and_ors_their_data():
    line, _, _ = make_line(3)
    reply = one(line, Cmd.BRD, 0, R.TYPE, b"\0\0")
    assert reply.wkc == 3 and reply.data[0] == R.ESC_TYPE
    assert reply.adp == 3  # every slave increments ADP


def test_auto_increment_addresses_the_slave_where_adp_reaches_zero():
    line, _, _ = make_line(3)
    assert one(line, Cmd.APWR, -1, R.STATION_ADDRESS, b"\x02\x10").wkc == 1
    assert line.escs[1].station == 0x1002 and line.escs[0].station == 0
    reply = one(line, Cmd.APRD, -1, R.STATION_ADDRESS, b"\0\0")
    assert reply.data == b"\x02\x10" and reply.wkc == 1
    assert one(line, Cmd.APRD, -3, R.STATION_ADDRESS, b"\0\0").wkc == 0  # nobody there


@pytest.mark.parametrize(("cmd", "wkc"), [(Cmd.FPRD, 1), (Cmd.FPWR, 1), (Cmd.FPRW, 3)])
def test_configured_address_wkc(cmd, wkc):
    line, _, _ = make_line(3)
    addressed(line)
    assert one(line, cmd, 0x1002, 0x0F80, b"\x55").wkc == wkc
    assert one(line, cmd, 0x1009, 0x0F80, b"\x55").wkc == 0


def test_fprw_returns_the_old_value_and_stores_the_new():
    line, _, _ = make_line(1)
    addressed(line)
    one(line, Cmd.FPWR, 0x1001, 0x0F80, b"\x11")
    assert one(line, Cmd.FPRW, 0x1001, 0x0F80, b"\x22").data == b"\x11"
    assert line.escs[0].mem[0x0F80] == 0x22


@pytest.mark.parametrize(("ado", "size"), [(R.TYPE, 8), (R.DL_STATUS, 2), (R.AL_STATUS, 6),
                                           (R.STATION_ALIAS, 2)])
def test_read_only_registers_ignore_master_writes(ado, size):
    line, _, _ = make_line(1)
    before = bytes(line.escs[0].mem[ado:ado + size])
    assert one(line, Cmd.BWR, 0, ado, b"\xAA" * size).wkc == 1
    assert bytes(line.escs[0].mem[ado:ado + size]) == before


def test_info_block_and_dc_feature_bit():
    line, _, _ = make_line(1)
    data = one(line, Cmd.APRD, 0, R.TYPE, bytes(10)).data
    assert data[0] == 0x11 and data[4] == 3 and struct.unpack_from("<H", data, 8)[0] & 0x04
    line, _, _ = make_line(1, dc=False)
    assert not struct.unpack_from("<H", one(line, Cmd.APRD, 0, R.FEATURES, b"\0\0").data)[0] & 4


def test_dl_status_shows_the_last_slave_with_port_1_closed():
    """SOEM's topology: (0x0110 & 0x0C00) == 0x0800 is 'port 1 open and communicating'."""
    line, _, _ = make_line(3)
    status = [struct.unpack("<H", one(line, Cmd.APRD, -i, R.DL_STATUS, b"\0\0").data)[0]
              for i in range(3)]
    assert [(s & 0x0300) == 0x0200 for s in status] == [True] * 3
    assert [(s & 0x0C00) == 0x0800 for s in status] == [True, True, False]


def test_al_control_goes_to_process_a_and_al_status_comes_back():
    line, outbox, _ = make_line(2)
    one(line, Cmd.BWR, 0, R.AL_CONTROL, b"\x11")
    assert outbox == [(messages.AL_CONTROL, 0, 0x11), (messages.AL_CONTROL, 1, 0x11)]
    line.escs[1].set_al_status(0x12, 0x8204)
    data = one(line, Cmd.APRD, -1, R.AL_STATUS, bytes(6)).data
    assert struct.unpack("<HHH", data) == (0x12, 0, 0x8204)


# ---- SII EEPROM interface -----------------------------------------------------------------
def test_eeprom_read_command_copies_8_bytes_per_slave():
    """Notes: command 1 at 0x0502 with the word address at 0x0504 copies 8 bytes to 0x0508 and
    leaves 0x0502 = 0x0040; each slave keeps its own data register (SOEM interleaves)."""
    line, _, _ = make_line(2)
    addressed(line)
    for station in (0x1001, 0x1002):
        one(line, Cmd.FPWR, station, R.EEPROM_CONTROL, struct.pack("<HHH", 0x0100, 0x0A, 0))
    for i, station in enumerate((0x1001, 0x1002)):
        data = one(line, Cmd.FPRD, station, R.EEPROM_CONTROL, bytes(14)).data
        assert struct.unpack_from("<H", data)[0] == 0x0040
        assert struct.unpack_from("<I", data, 6)[0] == 0x100 + i  # product code, word 0x0A


# ---- FMMUs and process data --------------------------------------------------------------
def configure(line: Line, logical: int = 0x10000) -> None:
    """SM2 outputs (2 bytes) and SM3 inputs (4 bytes) of every slave in one logical image."""
    addressed(line)
    n = len(line.escs)
    for i in range(n):
        st = 0x1001 + i
        one(line, Cmd.FPWR, st, R.SM0 + 16, struct.pack("<HHBBBB", 0x1100, 2, 0x64, 0, 1, 0))
        one(line, Cmd.FPWR, st, R.SM0 + 24, struct.pack("<HHBBBB", 0x1180, 4, 0x20, 0, 1, 0))
        out = struct.pack("<IHBBHBBB3x", logical + 2 * i, 2, 0, 7, 0x1100, 0, 2, 1)
        inp = struct.pack("<IHBBHBBB3x", logical + 2 * n + 4 * i, 4, 0, 7, 0x1180, 0, 1, 1)
        one(line, Cmd.FPWR, st, R.FMMU0, out + inp)


def test_sm_registers_go_to_process_a_when_they_change():
    """The slave checks its sync managers at INIT -> PREOP and PREOP -> SAFEOP (seed 001 §9.2):
    A gets SM0..SM3 as written; the same registers again (SOEM's repeat toggle, a rewrite)
    send nothing."""
    line, outbox, _ = make_line(1)
    addressed(line)
    outbox.clear()  # the station address written (test_fastcat_address_wire.py)
    sm0 = struct.pack("<HHBBBB", 0x1000, 128, 0x26, 0, 1, 0)
    one(line, Cmd.FPWR, 0x1001, R.SM0, sm0)
    assert outbox == [(messages.SM, 0, ((0x1000, 128, 0x26, True), (0, 0, 0, False),
                                        (0, 0, 0, False), (0, 0, 0, False)))]
    outbox.clear()
    one(line, Cmd.FPWR, 0x1001, R.SM0, sm0)
    assert outbox == []


def test_lrw_wkc_is_three_per_slave_and_data_moves_both_ways():
    line, outbox, _ = make_line(3)
    configure(line)
    for i, esc in enumerate(line.escs):
        esc.set_inputs(struct.pack("<I", 0xA0 + i))
    outbox.clear()
    image = b"".join(struct.pack("<H", 0x500 + i) for i in range(3)) + bytes(12)
    reply = run(line, Request.logical(Cmd.LRW, 0x10000, image))[0]
    assert reply.wkc == 9
    assert [struct.unpack_from("<I", reply.data, 6 + 4 * i)[0] for i in range(3)] == [
        0xA0, 0xA1, 0xA2]
    assert outbox == [(messages.OUTPUTS, i, struct.pack("<H", 0x500 + i)) for i in range(3)]
    assert [e.exchanges for e in line.escs] == [1, 1, 1]


@pytest.mark.parametrize(("cmd", "wkc"), [(Cmd.LRD, 3), (Cmd.LWR, 3), (Cmd.LRW, 9)])
def test_lrd_lwr_wkc(cmd, wkc):
    line, _, _ = make_line(3)
    configure(line)
    assert run(line, Request.logical(cmd, 0x10000, bytes(18)))[0].wkc == wkc


def test_unchanged_outputs_are_not_reported_again():
    line, outbox, _ = make_line(1)
    configure(line)
    run(line, Request.logical(Cmd.LRW, 0x10000, b"\x01\x00" + bytes(4)))
    outbox.clear()
    run(line, Request.logical(Cmd.LRW, 0x10000, b"\x01\x00" + bytes(4)))
    assert outbox == []


def test_bit_granular_fmmu_maps_single_bits():
    line, _, _ = make_line(1)
    addressed(line)
    # logical bits 3..4 of byte 0x20 onto physical bits 0..1 of 0x1100 (outputs)
    fmmu = struct.pack("<IHBBHBBB3x", 0x20, 1, 3, 4, 0x1100, 0, 2, 1)
    one(line, Cmd.FPWR, 0x1001, R.FMMU0, fmmu)
    reply = run(line, Request.logical(Cmd.LWR, 0x20, b"\x18"))[0]
    assert reply.wkc == 1 and line.escs[0].mem[0x1100] == 0x03


def test_vanished_slaves_leave_the_frame_untouched_and_count_as_wkc_error():
    line, _, _ = make_line(3)
    configure(line)
    line.set_link(1, False)
    assert one(line, Cmd.BRD, 0, R.TYPE, b"\0\0").wkc == 1
    reply = run(line, Request.logical(Cmd.LRW, 0x10000, bytes(18)))[0]
    assert reply.wkc == 3 and line.wkc_errors == 1
    line.set_link(0, True)  # every cut from 0 on healed
    assert one(line, Cmd.BRD, 0, R.TYPE, b"\0\0").wkc == 3
    line.set_link(0, False)
    assert not line.process(D.build([Request(Cmd.BRD, 0, 0, b"\0\0")]))  # master link down


def test_access_past_the_64_kib_keeps_the_frame_size():
    line, _, _ = make_line(1)
    addressed(line)
    frame = D.build([Request(Cmd.FPWR, 0x1001, 0xFFFE, b"\x01\x02\x03\x04"),
                     Request(Cmd.FPRD, 0x1001, 0xFFFE, bytes(4))])
    size = len(frame)
    assert line.process(frame) and len(frame) == size
    assert D.replies(frame)[1].data == b"\x01\x02\x00\x00"
    assert len(line.escs[0].mem) == R.MEMORY_SIZE


def test_random_datagrams_never_break_the_line():
    """Whatever a master (or noise) sends: the answer has the frame's size, or the frame is
    rejected as malformed; the ESC memory stays 64 KiB."""
    import random

    rng = random.Random(8)
    line, _, _ = make_line(3)
    configure(line)
    for _ in range(1000):
        requests = [Request(rng.randrange(16), rng.randrange(0x10000), rng.choice(
            [rng.randrange(0x10000), rng.randrange(0x1000), 0x0120, 0x0502, 0x0800, 0x0910]),
            rng.randbytes(rng.randrange(0, 40))) for _ in range(rng.randrange(1, 4))]
        frame = D.build(requests)
        size = len(frame)
        line.process(frame)
        assert len(frame) == size
    for _ in range(500):
        noise = bytearray(D.build([Request(Cmd.BRD, 0, 0, b"\0\0")])[:16]) + rng.randbytes(40)
        with contextlib.suppress(D.FrameError):
            line.process(noise)
    assert all(len(esc.mem) == R.MEMORY_SIZE for esc in line.escs)
