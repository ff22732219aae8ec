"""SDO complete access over the CoE mailbox (ETG.1000.6: bit 0x10 of the SDO command).

A whole object in one transfer, laid out as SOEM's ``ecx_readPDOmapCA`` reads it (sub 0 as
U8 padded to 16 bits, then the subs up to the one sub 0 names) and as SOES writes it (bit types
packed, a byte type from the next byte). Served only by a slave that announces it (SII CoE
details bit 0x20); the TRS-CAT does (seed 001 §9 / §9.3: "SDO information service con
accesso completo e la possibilità di segmentare i frame"). The client below does what SOEM's
``ecx_SDOread`` / ``ecx_SDOwrite`` with ``CA = TRUE`` put on the wire.
"""

from __future__ import annotations

import struct

import pytest
from test_coe import OdFace, OdModel, mbx

from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.faces.base import COE_SDO, COE_SDO_INFO
from devices.od import AbortCode, Access, DataType, OdEntry

COE_COMPLETE_ACCESS = 0x20  # SII GENERAL CoE details, ETG.2010


class Aborted(Exception):
    def __init__(self, code: int) -> None:
        super().__init__(f"abort 0x{code:08X}")
        self.code = code


def _request(index: int, sub: int, command: int, tail: bytes = bytes(4)) -> bytes:
    return mbx((struct.pack("<HBHB", 0x2000, command, index, sub) + tail).hex(" "))


def _check(reply: bytes) -> bytes:
    if reply[8] == 0x80:
        raise Aborted(struct.unpack_from("<I", reply, 12)[0])
    return reply


def ca_upload(srv: CoeServer, index: int, sub: int = 0) -> bytes:
    """SOEM's ecx_SDOread(CA = TRUE): 0x50, then segments 0x60 / 0x70 until all is there."""
    (reply,) = srv.handle(_request(index, sub, 0x50))
    command = _check(reply)[8]
    assert command & 0x10, f"complete access bit not echoed: {command:#x}"
    assert struct.unpack_from("<HB", reply, 9) == (index, sub)
    if command & 0x02:  # expedited
        return reply[12:12 + 4 - (command >> 2 & 3)]
    size = struct.unpack_from("<I", reply, 12)[0]
    data = reply[16:]
    toggle = 0
    while len(data) < size:
        (seg,) = srv.handle(mbx(f"00 20 {0x60 | toggle:02x} 00 00 00 00 00 00 00"))
        seg_command = _check(seg)[8]
        assert seg_command & 0x10 == toggle
        chunk = seg[9:]
        if seg_command & 0x01 and len(chunk) == 7:
            chunk = chunk[:7 - (seg_command >> 1 & 7)]
        data += chunk
        toggle ^= 0x10
    assert len(data) == size
    return data


def ca_download(srv: CoeServer, index: int, sub: int, data: bytes) -> None:
    """SOEM's ecx_SDOwrite(CA = TRUE): always a normal 0x31 initiate (never expedited), the
    rest in segments of the mailbox's size."""
    room = srv.mailbox_size - 16
    first, rest = data[:room], data[room:]
    (reply,) = srv.handle(_request(index, sub, 0x31, struct.pack("<I", len(data)) + first))
    assert _check(reply)[8] == 0x70, reply.hex(" ")  # download response, CA echoed
    assert struct.unpack_from("<HB", reply, 9) == (index, sub)
    toggle = 0
    while rest:
        chunk, rest = rest[:room + 7], rest[room + 7:]
        command = toggle | (0x01 if not rest else 0)
        if not rest and len(chunk) < 7:
            command |= (7 - len(chunk)) << 1
            chunk = chunk.ljust(7, b"\0")
        (seg,) = srv.handle(mbx(f"00 20 {command:02x} " + chunk.hex(" ")))
        assert _check(seg)[8] == 0x20 | toggle
        toggle ^= 0x10


def abort_of(call, *args) -> int:
    with pytest.raises(Aborted) as info:
        call(*args)
    return info.value.code


# ---- byte fixtures on a small dictionary -------------------------------------------------------
class CaFace(OdFace):
    coe_details = COE_SDO | COE_SDO_INFO | COE_COMPLETE_ACCESS


class CaModel(OdModel):
    """OdModel plus an array of U16 (written whole) and a record mixing bits and bytes."""

    def __init__(self) -> None:
        super().__init__()
        od = self.od
        od.add(OdEntry(0x2100, 0, "Count", DataType.UNSIGNED8, Access.RW, 2, high=3))
        for sub, value in ((1, 0x1111), (2, 0x2222), (3, 0x3333)):
            od.add(OdEntry(0x2100, sub, f"Word {sub}", DataType.UNSIGNED16, Access.RW, value,
                           high=0x7FFF))
        od.add(OdEntry(0x2200, 0, "Highest sub", DataType.UNSIGNED8, Access.RO, 4))
        od.add(OdEntry(0x2200, 1, "Byte", DataType.UNSIGNED8, Access.RO, 0xAB))
        od.add(OdEntry(0x2200, 2, "Bit a", DataType.BOOLEAN, Access.RO, 1))
        od.add(OdEntry(0x2200, 3, "Bit b", DataType.BOOLEAN, Access.RO, 1))
        od.add(OdEntry(0x2200, 4, "Word", DataType.UNSIGNED16, Access.RO, 0xBEEF))


def ca_server(mailbox_size: int = 128) -> tuple[CoeServer, CaModel]:
    model = CaModel()
    return CoeServer(CaFace(), model, mailbox_size), model


def test_upload_pads_sub_0_to_16_bits_and_stops_at_the_sub_it_names():
    """0x2100: sub 0 = 2 -> ``02 00`` then subs 1 and 2 (sub 3 exists, not counted): six
    bytes, a normal response with the CA bit (0x51)."""
    srv, _ = ca_server()
    (reply,) = srv.handle(mbx("00 20 50 00 21 00 00 00 00 00"))
    assert reply.hex(" ") == ("10 00 00 00 00 13 00 30 51 00 21 00 06 00 00 00 "
                              "02 00 11 11 22 22")


def test_upload_from_sub_1_leaves_sub_0_out_and_small_answers_are_expedited():
    srv, _ = ca_server()
    (reply,) = srv.handle(mbx("00 20 50 00 21 01 00 00 00 00"))
    assert reply.hex(" ") == "0a 00 00 00 00 13 00 30 53 00 21 01 11 11 22 22"


def test_upload_packs_bits_and_starts_a_byte_type_on_the_next_byte():
    """0x2200: ``04 00`` | AB | bits a, b in one byte (0x03) | EF BE."""
    srv, _ = ca_server()
    assert ca_upload(srv, 0x2200).hex(" ") == "04 00 ab 03 ef be"


def test_upload_of_a_variable_alone_is_its_own_size():
    """An object without subs (VAR): its value as it is, sub 0 not padded (SOES)."""
    srv, _ = ca_server()
    assert ca_upload(srv, 0x1000) == struct.pack("<I", 0x1389)


def test_segmented_upload_with_a_small_mailbox():
    srv, model = ca_server(mailbox_size=24)
    model.od.poke(0x2100, 0, 3)
    assert ca_upload(srv, 0x2100) == bytes.fromhex("03 00 11 11 22 22 33 33")


def test_download_writes_sub_0_then_the_subs_it_names():
    srv, model = ca_server()
    ca_download(srv, 0x2100, 0, bytes.fromhex("03 00 01 00 02 00 03 00"))
    assert [model.od.peek(0x2100, s) for s in range(4)] == [3, 1, 2, 3]


def test_segmented_download_with_a_small_mailbox():
    srv, model = ca_server(mailbox_size=20)  # 4 bytes in the initiate, then 7 + ...
    ca_download(srv, 0x2100, 0, bytes.fromhex("03 00 0a 00 0b 00 0c 00"))
    assert [model.od.peek(0x2100, s) for s in range(4)] == [3, 10, 11, 12]


def test_download_from_sub_1_keeps_sub_0():
    srv, model = ca_server()
    ca_download(srv, 0x2100, 1, bytes.fromhex("05 00 06 00"))
    assert [model.od.peek(0x2100, s) for s in range(4)] == [2, 5, 6, 0x3333]


def test_a_download_refused_midway_writes_nothing():
    """Sub 3 above its range (0x7FFF): abort 0x06090031 on sub 3 and no sub changed."""
    srv, model = ca_server()
    code = abort_of(ca_download, srv, 0x2100, 0, bytes.fromhex("03 00 01 00 02 00 00 80"))
    assert code == AbortCode.VALUE_TOO_HIGH
    assert [model.od.peek(0x2100, s) for s in range(4)] == [2, 0x1111, 0x2222, 0x3333]


@pytest.mark.parametrize(("data", "code"), [
    ("02 00 01 00", AbortCode.LENGTH_TOO_LOW),  # sub 0 = 2 names two words, one sent
    ("01 00 01 00 02 00", AbortCode.LENGTH_TOO_HIGH),  # sub 0 = 1 names one word, two sent
])
def test_a_download_of_the_wrong_length_aborts(data, code):
    srv, model = ca_server()
    assert abort_of(ca_download, srv, 0x2100, 0, bytes.fromhex(data)) == code
    assert model.od.peek(0x2100, 1) == 0x1111


def test_read_only_subs_may_be_sent_unchanged_but_not_changed():
    srv, model = ca_server()
    ca_download(srv, 0x2200, 0, bytes.fromhex("04 00 ab 03 ef be"))  # as it is: accepted
    assert abort_of(ca_download, srv, 0x2200, 0, bytes.fromhex("04 00 ac 03 ef be")) == \
        AbortCode.READ_ONLY
    assert model.od.peek(0x2200, 1) == 0xAB


@pytest.mark.parametrize("command", ["50", "31"])
def test_complete_access_from_a_sub_above_1_is_refused(command):
    """ETG.1000.6 / SOES: a complete access starts at sub 0 or 1, else 0x06010000."""
    srv, _ = ca_server()
    (reply,) = srv.handle(mbx(f"00 20 {command} 00 21 02 04 00 00 00 01 00 02 00"))
    assert reply[8:].hex(" ") == "80 00 21 02 00 00 01 06"


def test_an_object_with_a_string_is_refused_with_0x06010004():
    """ETG.1000.6 0x06010004: complete access not supported for objects of variable length."""
    srv, _ = ca_server()
    assert abort_of(ca_upload, srv, 0x1008) == 0x0601_0004


def test_a_missing_object_aborts_as_a_single_access_would():
    srv, _ = ca_server()
    assert abort_of(ca_upload, srv, 0x3000) == AbortCode.NO_OBJECT


def test_a_slave_that_does_not_announce_it_refuses_it():
    """No CoE details bit 0x20: abort 0x06010000, as a device without complete access does."""
    srv = CoeServer(OdFace(), CaModel())
    assert abort_of(ca_upload, srv, 0x2100) == AbortCode.UNSUPPORTED_ACCESS
