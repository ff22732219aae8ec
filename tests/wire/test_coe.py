"""The CoE mailbox service against byte fixtures (ETG.1000.6 as SOEM's ec_coe.c reads it).

Mailbox header ``length, address, channel/priority, type | counter << 4``; CoE header
``number | service << 12``; SDO ``command, index, sub, data``. The fixtures are whole mailbox
messages, request in, reply out. Aborts carry the DS301 codes of devices/od.py with CoE
service 2 (ethercat-wire-notes.md: a service-3 abort broke SOEM). Emergencies: the FastCAT's
``FF00 / 81 / 02 00 00 04 00`` of seed 000 §7.1 when module 2 stops answering, the TRS-CAT's
(seed 001 §9.3.7, with 0x10F3:5 bit 0) and the CPX-E-EC's (seed 002 §2.5.3).
"""

from __future__ import annotations

import struct
from typing import ClassVar

import pytest
from test_faces import line_rig

from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.faces import face_for
from app.ethercat_wire.faces.base import Face
from devices.ethercat import parse_emergency_frame
from devices.od import AbortCode, Access, DataType, ObjectDictionary, OdEntry

LONG = "FieldRig EtherCAT wire test!!!"  # 30 bytes: a normal upload; segmented with a small mailbox


class OdModel:
    """A slave model reduced to what the CoE service touches: a dictionary on the line."""

    KIND = "test"
    device_id = "dev"

    def __init__(self) -> None:
        od = ObjectDictionary()
        od.add(OdEntry(0x1000, 0, "Device type", DataType.UNSIGNED32, Access.RO, 0x1389))
        od.add(OdEntry(0x1008, 0, "Device name", DataType.VISIBLE_STRING, Access.RO, LONG))
        od.add(OdEntry(0x2000, 0, "Setting", DataType.UNSIGNED8, Access.RW, 7, high=100,
                       pdo_mappable=True))
        od.add(OdEntry(0x2001, 0, "Label", DataType.VISIBLE_STRING, Access.RW, ""))
        od.add(OdEntry(0x6000, 0, "N° of entries", DataType.UNSIGNED8, Access.RO, 2))
        for sub in (1, 2):
            od.add(OdEntry(0x6000, sub, f"Input {sub}", DataType.BOOLEAN, Access.RO, 0,
                           pdo_mappable=True))
        od.add(OdEntry(0x1C12, 0, "RxPDO assign", DataType.UNSIGNED8, Access.RO, 0))
        self.od = od

    def reachable(self) -> bool:
        return True


class OdFace(Face):
    kind = "test"
    name = "Test"
    group = order_code = "Test"
    identity_defaults: ClassVar[tuple[int, int, int]] = (1, 2, 3)


def server(mailbox_size: int = 128) -> tuple[CoeServer, OdModel]:
    model = OdModel()
    return CoeServer(OdFace(), model, mailbox_size), model


def mbx(payload: str, counter: int = 1, mbx_type: int = 3) -> bytes:
    data = bytes.fromhex(payload)
    return struct.pack("<HHBB", len(data), 0, 0, mbx_type | counter << 4) + data


def hexes(messages: list[bytes]) -> list[str]:
    return [m.hex(" ") for m in messages]


# ---- SDO upload / download ----------------------------------------------------------------
def test_expedited_upload():
    srv, _ = server()
    assert hexes(srv.handle(mbx("00 20 40 00 10 00 00 00 00 00"))) == [
        "0a 00 00 00 00 13 00 30 43 00 10 00 89 13 00 00"]


def test_expedited_upload_size_is_the_objects_type():
    """An U8 answers one byte (0x4F): a 4-byte answer to 0x1C00:0 broke SOEM's config_map."""
    srv, _ = server()
    assert hexes(srv.handle(mbx("00 20 40 00 1c 00 00 00 00 00"))) == [
        "0a 00 00 00 00 13 00 30 4f 00 1c 00 04 00 00 00"]


def test_normal_upload():
    srv, _ = server()
    (reply,) = srv.handle(mbx("00 20 40 08 10 00 00 00 00 00"))
    assert reply[:16].hex(" ") == "28 00 00 00 00 13 00 30 41 08 10 00 1e 00 00 00"
    assert reply[16:] == LONG.encode()


def test_segmented_upload():
    """Mailbox of 24 bytes: 8 data bytes in the initiate answer, then segments of up to 15
    (toggle 0x10 alternating); the last one (7 bytes, none unused) has bit 0 set."""
    srv, _ = server(mailbox_size=24)
    (first,) = srv.handle(mbx("00 20 40 08 10 00 00 00 00 00"))
    assert first.hex(" ") == "12 00 00 00 00 13 00 30 41 08 10 00 1e 00 00 00 " + \
        LONG[:8].encode().hex(" ")
    (seg1,) = srv.handle(mbx("00 20 60 00 00 00 00 00 00 00", counter=2))
    assert seg1.hex(" ") == "12 00 00 00 00 23 00 30 00 " + LONG[8:23].encode().hex(" ")
    (seg2,) = srv.handle(mbx("00 20 70 00 00 00 00 00 00 00", counter=3))
    assert seg2.hex(" ") == "0a 00 00 00 00 33 00 30 11 " + LONG[23:].encode().hex(" ")
    assert srv.handle(mbx("00 20 60 00 00 00 00 00 00 00", counter=4)) == [
        mbx("00 20 80 00 00 00 01 00 04 05", counter=4)]  # nothing left: invalid command


def test_segmented_upload_pads_a_short_last_segment():
    """A last segment under 7 bytes is padded; command bits 1-3 say how many are unused."""
    srv, model = server(mailbox_size=24)
    model.od.poke(0x1008, 0, LONG[:11])
    srv.handle(mbx("00 20 40 08 10 00 00 00 00 00"))
    (last,) = srv.handle(mbx("00 20 60 00 00 00 00 00 00 00", counter=2))
    assert last.hex(" ") == "0a 00 00 00 00 23 00 30 09 " + \
        LONG[8:11].encode().hex(" ") + " 00 00 00 00"


def test_expedited_download():
    srv, model = server()
    assert hexes(srv.handle(mbx("00 20 2f 00 20 00 2a 00 00 00"))) == [
        "0a 00 00 00 00 13 00 30 60 00 20 00 00 00 00 00"]
    assert model.od.peek(0x2000, 0) == 0x2A


def test_normal_and_segmented_download():
    srv, model = server(mailbox_size=24)
    text = b"written in 3 parts!!"  # 20 bytes: 8 in the initiate request, 7 + 5 in segments
    initiate = "00 20 21 01 20 00 14 00 00 00 " + text[:8].hex(" ")
    assert hexes(srv.handle(mbx(initiate))) == [
        "0a 00 00 00 00 13 00 30 60 01 20 00 00 00 00 00"]
    assert hexes(srv.handle(mbx("00 20 00 " + text[8:15].hex(" "), counter=2))) == [
        "0a 00 00 00 00 23 00 30 20 00 00 00 00 00 00 00"]
    last = "00 20 15 " + text[15:].hex(" ") + " 00 00"  # toggle, 2 unused, last
    assert hexes(srv.handle(mbx(last, counter=3))) == [
        "0a 00 00 00 00 33 00 30 30 00 00 00 00 00 00 00"]
    assert model.od.peek(0x2001, 0) == text.decode()
    srv2, model2 = server()
    assert srv2.handle(mbx("00 20 21 01 20 00 05 00 00 00 " + b"whole".hex(" ")))[0][8] == 0x60
    assert model2.od.peek(0x2001, 0) == "whole"


@pytest.mark.parametrize(("request_hex", "code"), [
    ("00 20 40 00 30 00 00 00 00 00", AbortCode.NO_OBJECT),  # 0x3000 does not exist
    ("00 20 40 00 10 05 00 00 00 00", AbortCode.NO_SUBINDEX),  # 0x1000:5
    ("00 20 23 00 10 00 01 00 00 00", AbortCode.READ_ONLY),  # write 0x1000
    ("00 20 2b 00 20 00 01 00 00 00", AbortCode.LENGTH_TOO_HIGH),  # 2 bytes into an U8
    ("00 20 2f 00 20 00 65 00 00 00", AbortCode.VALUE_TOO_HIGH),  # 101 > 100
    ("00 20 50 00 10 00 00 00 00 00", AbortCode.UNSUPPORTED_ACCESS),  # complete access
    ("00 20 e0 00 10 00 00 00 00 00", AbortCode.INVALID_COMMAND),  # no such command
    ("00 20 21 00 10 00 10 00 00 00 00 00", AbortCode.READ_ONLY),  # segmented to a RO object
])
def test_abort_codes_with_coe_service_2(request_hex, code):
    srv, _ = server()
    index_sub = bytes.fromhex(request_hex)[3:6].hex(" ")
    expected = "00 20 80 " + index_sub + " " + struct.pack("<I", code).hex(" ")
    assert srv.handle(mbx(request_hex)) == [mbx(expected)]


def test_toggle_not_alternated_aborts():
    srv, _ = server(mailbox_size=24)
    srv.handle(mbx("00 20 40 08 10 00 00 00 00 00"))
    assert srv.handle(mbx("00 20 70 00 00 00 00 00 00 00", counter=2)) == [
        mbx("00 20 80 08 10 00 00 00 03 05", counter=2)]


def test_mailbox_counter_runs_1_to_7():
    srv, _ = server()
    counters = [srv.handle(mbx("00 20 40 00 10 00 00 00 00 00"))[0][5] >> 4
                for _ in range(9)]
    assert counters == [1, 2, 3, 4, 5, 6, 7, 1, 2]


def test_other_mailbox_protocols_get_a_mailbox_error():
    """EoE (type 2) is not served: mailbox error, type 0, detail 0x0002."""
    srv, _ = server()
    assert hexes(srv.handle(mbx("00 00 00 00", mbx_type=2))) == ["04 00 00 00 00 10 01 00 02 00"]


def test_no_dictionary_no_answer():
    srv, model = server()
    model.od = None
    assert srv.handle(mbx("00 20 40 00 10 00 00 00 00 00")) == []


# ---- SDO information ------------------------------------------------------------------------
def test_od_list_of_all_objects():
    srv, _ = server()
    (reply,) = srv.handle(mbx("00 80 01 00 00 00 01 00"))
    indices = [0x1000, 0x1008, 0x1C00, 0x1C12, 0x2000, 0x2001, 0x6000]
    body = "00 80 02 00 00 00 01 00 " + struct.pack(f"<{len(indices)}H", *indices).hex(" ")
    assert reply == mbx(body)


def test_od_list_in_fragments():
    """A mailbox of 24 bytes carries 6 words per fragment: list type + 5, then the rest."""
    srv, _ = server(mailbox_size=24)
    first, second = srv.handle(mbx("00 80 01 00 00 00 01 00"))
    assert first[6:12].hex(" ") == "00 80 82 00 01 00"  # incomplete, 1 fragment left
    assert second[6:12].hex(" ") == "00 80 02 00 00 00"
    assert struct.unpack("<2H", second[12:]) == (0x2001, 0x6000)


def test_od_list_lengths_and_pdo_lists():
    srv, _ = server()
    (lengths,) = srv.handle(mbx("00 80 01 00 00 00 00 00"))
    assert struct.unpack("<6H", lengths[12:]) == (0, 7, 1, 1, 0, 0)
    (tx,) = srv.handle(mbx("00 80 01 00 00 00 03 00"))
    assert struct.unpack("<2H", tx[12:]) == (3, 0x6000)


def test_object_description():
    srv, _ = server()
    (var,) = srv.handle(mbx("00 80 03 00 00 00 00 20"))
    assert var == mbx("00 80 04 00 00 00 00 20 05 00 00 07 " + b"Setting".hex(" "))
    (array,) = srv.handle(mbx("00 80 03 00 00 00 00 60"))
    assert array[12:18].hex(" ") == "00 60 01 00 02 08"  # BOOLEAN, max sub 2, ARRAY


def test_entry_description():
    """Access word: read 0x07 + write 0x38 + RxPDO mappable 0x40 (ETG.1000.6 Table 59)."""
    srv, _ = server()
    (reply,) = srv.handle(mbx("00 80 05 00 00 00 00 20 00 07"))
    assert reply == mbx("00 80 06 00 00 00 00 20 00 07 05 00 08 00 7f 00 " +
                        b"Setting".hex(" "))


@pytest.mark.parametrize(("request_hex", "code"), [
    ("00 80 03 00 00 00 00 30", AbortCode.NO_OBJECT),
    ("00 80 05 00 00 00 00 20 09 07", AbortCode.NO_SUBINDEX),
])
def test_sdo_info_errors(request_hex, code):
    srv, _ = server()
    assert srv.handle(mbx(request_hex)) == [
        mbx("00 80 07 00 00 00 " + struct.pack("<I", code).hex(" "))]


# ---- the slave models ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def rig():
    rig = line_rig("PREOP")
    rig.devices["master"].set_external(True)  # the emergencies stay in the slaves' mailboxes
    return rig


@pytest.mark.parametrize("device", ["fastcat", "trscat", "cpx", "drive_ecat-ecat"])
def test_identity_read_over_the_mailbox(rig, device):
    model = rig.devices[device]
    face = face_for(model)
    srv = CoeServer(face, model)
    (reply,) = srv.handle(mbx("00 20 40 18 10 02 00 00 00 00"))
    assert reply[8] == 0x43  # expedited, 4 bytes
    assert int.from_bytes(reply[12:16], "little") == face.od(model).peek(0x1018, 2)


@pytest.mark.parametrize(("index", "sub", "access"), [
    (0xF030, 0, 0x000F), (0xF030, 1, 0x000F), (0xF030, 8, 0x000F),  # "R-WPS"
    (0xF050, 1, 0x0007), (0xF700, 1, 0x003F)])
def test_trscat_entry_access_as_its_tables_print_it(rig, index, sub, access):
    """Seed 001 §9.3.2: 0xF030 is "R-WPS" ("RO e WRITE in PRE-OP"): an entry description
    says read in every state, write in PRE-OP only (ETG.1000.6 Table 59 bits 0..2, 3), as
    the device refuses a write in SAFE-OP / OP; 0xF050 RO, 0xF700 RW (§9.3.5)."""
    model = rig.devices["trscat"]
    srv = CoeServer(face_for(model), model)
    request = f"00 80 05 00 00 00 {index & 0xFF:02x} {index >> 8:02x} {sub:02x} 07"
    (reply,) = srv.handle(mbx(request))
    assert reply[6:10].hex(" ") == "00 80 06 00"
    assert int.from_bytes(reply[20:22], "little") == access


@pytest.mark.parametrize(("index", "sub", "access"), [
    (0x1C12, 0, 0x000F), (0x1C13, 1, 0x000F), (0x1600, 1, 0x000F), (0x1A02, 0, 0x000F),
    (0x6040, 0, 0x007F), (0x6041, 0, 0x0087), (0x1018, 1, 0x0007)])
def test_drive_entry_access_as_it_answers_writes(rig, index, sub, access):
    """Seed 004 ch. 5: the PDO mapping and assignment are configured in PRE-OP ("P -> S: Il
    Master configura ... la mappatura dei process data"); the drive refuses their writes in
    SAFE-OP / OP with 0x08000022, so their entry description says write in PRE-OP only
    (ETG.1000.6 Table 59), not 0x003F; the controlword RxPDO-mappable, the statusword TxPDO."""
    model = rig.devices["drive_ecat-ecat"]
    srv = CoeServer(face_for(model), model)
    request = f"00 80 05 00 00 00 {index & 0xFF:02x} {index >> 8:02x} {sub:02x} 07"
    (reply,) = srv.handle(mbx(request))
    assert reply[6:10].hex(" ") == "00 80 06 00"
    assert int.from_bytes(reply[20:22], "little") == access


def test_fastcat_module_2_stops_answering(rig):
    """Seed 000 §7.1: 'CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00)'."""
    model = rig.devices["fastcat"]
    srv = CoeServer(face_for(model), model)
    model.take_emergencies()
    rig.apply("fastcat/2", "module_failure", {"active": True})
    rig.run_until(rig.clock.now_us + 100_000)
    frames = model.take_emergencies()
    assert [srv.emergency(f).hex(" ") for f in frames] == [
        "0a 00 00 00 00 13 00 10 00 ff 81 02 00 00 04 00"]
    (reset,) = srv.handle(mbx("00 20 2f 00 52 01 01 00 00 00"))  # 0x5200:1 Reset fault
    assert reset[8] == 0x60


def enable_emergencies(srv: CoeServer) -> None:
    """0x10F3:5 bit 0 (ETG.1020: messages also sent as emergencies), written over the wire."""
    width = srv.face.entry(srv.model, 0x10F3, 5).bit_length // 8
    command = 0x23 | (4 - width) << 2
    assert srv.handle(mbx(f"00 20 {command:02x} f3 10 05 01 00 00 00"))[0][8] == 0x60


@pytest.fixture(scope="module")
def sti_rig():
    """The line with its CPX-E-EC on the I/O diagnostic interface (DIL 1 on, DIL 2 off): the
    one mode in which CPX errors send emergencies (seed 002 §2.5, docs/cpx-e-ec.md choice 33)."""
    rig = line_rig("PREOP", cpx_dil=(True, False))
    rig.devices["master"].set_external(True)
    return rig


@pytest.mark.parametrize(("line", "device", "fault", "code"), [
    ("rig", "trscat", ("trscat", "inject_fault", {"fault": "SOFTWARE_ERROR"}), 0x6100),  # §9.3.7
    ("sti_rig", "cpx", ("cpx/1", "short_circuit", {"on": True}), None),  # §2.5.3, KZS
])
def test_trscat_and_cpx_emergencies_travel_as_coe_service_1(request, line, device, fault, code):
    """Seed 001 §9.3.7 and seed 002 §2.5.3: the model's 8-byte frame behind CoE service 1."""
    rig = request.getfixturevalue(line)
    model = rig.devices[device]
    srv = CoeServer(face_for(model), model)
    enable_emergencies(srv)
    model.take_emergencies()
    rig.apply(*fault)
    rig.run_until(rig.clock.now_us + 300_000)
    frames = model.take_emergencies()
    assert frames
    message = srv.emergency(frames[0])
    assert message[:8].hex(" ") == f"0a 00 00 00 00 {srv.counter << 4 | 3:02x} 00 10"
    assert message[8:] == frames[0]
    got_code, register, _data = parse_emergency_frame(message[8:])
    assert register & 0x01  # 0x1001 generic bit
    if code is not None:
        assert got_code == code


def test_cpx_pdo_assignment_is_answered_in_address_order(rig):
    """Tab. 27 has no 0x1C12 / 0x1C13: the wire answers them (and 0x1C00) with the PDOs in
    the §2.3.1 order the images use, so a master's CoE mapping matches the SII's."""
    model = rig.devices["cpx"]
    face = face_for(model)
    srv = CoeServer(face, model)

    def upload(index: int, sub: int) -> int:
        (reply,) = srv.handle(mbx(f"00 20 40 {index & 0xFF:02x} {index >> 8:02x} {sub:02x} "
                                  "00 00 00 00"))
        assert reply[8] & 0x43 == 0x43, reply.hex(" ")  # expedited
        size = 4 - (reply[8] >> 2 & 3)
        return int.from_bytes(reply[12:12 + size], "little")

    assert [upload(0x1C00, s) for s in range(5)] == [4, 1, 2, 3, 4]
    for assign, pdos in ((0x1C12, face.rx_pdos(model)), (0x1C13, face.tx_pdos(model))):
        count = upload(assign, 0)
        assert [upload(assign, s) for s in range(1, count + 1)] == [p.index for p in pdos]
    (abort,) = srv.handle(mbx("00 20 2f 12 1c 00 00 00 00 00"))  # the assignment is fixed
    assert abort[8:].hex(" ") == "80 12 1c 00 02 00 01 06"


@pytest.mark.parametrize(("index", "name"), [
    (0x1600, "Receive PDO 1 mapping parameter"), (0x1A02, "Transmit PDO 3 mapping parameter"),
    (0x1003, "Pre-defined error field"), (0x1018, "Identity object")])
def test_the_drives_records_are_described_by_their_object_name(rig, index, name):
    """SDO Info 'get object description' names the object (seed 004 ch. 4: '0x1A02 Transmit
    PDO 3 Mapping Parameter', '0x1003 Pre Defined Error Field'), not its sub 0 ('Number of
    mapped objects', 'Number of errors'), as the drive's EDS does on its CANopen side."""
    model = rig.devices["drive_ecat-ecat"]
    srv = CoeServer(face_for(model), model)
    (reply,) = srv.handle(mbx("00 80 03 00 00 00 " + struct.pack("<H", index).hex(" ")))
    assert reply[8] & 0x7F == 0x04 and reply[18:].decode("latin-1") == name
