"""The TRS-CAT serves and announces SDO complete access (seed 001 §9 and §9.3: "il protocollo
CoE con il supporto del SDO information service con accesso completo e la possibilità di
segmentare i frame"); the other slaves of the line, whose seeds do not name it, refuse it.

Over the CoE server with the SOEM-like client of test_coe_complete_access: the PDO objects
uploaded whole, 0xF030 (the slot list that makes the PDO assignment, §9.3.2) downloaded whole
in PRE-OP, refused outside PRE-OP with the code a single write gets (0x08000022), and left as
it was when one of its subs is refused.
"""

from __future__ import annotations

import struct

import pytest
from test_coe_complete_access import COE_COMPLETE_ACCESS, abort_of, ca_download, ca_upload
from test_faces import line_rig

from app.ethercat_wire import esi
from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.faces import face_for
from devices.ethercat import AlState
from devices.od import AbortCode

IO_B, IO_E = 0x494F2D42, 0x494F2D45  # §9.3.2 idents: the integrated module, TRS-IO-E
U16, U32 = "H", "I"


@pytest.fixture
def preop():
    rig = line_rig("PREOP")
    rig.devices["master"].set_external(True)
    return rig


def trscat(rig, mailbox_size: int = 128) -> CoeServer:
    model = rig.devices["trscat"]
    return CoeServer(face_for(model), model, mailbox_size)


def whole(srv: CoeServer, index: int, fmt: str) -> bytes:
    """What a master expects by complete access, read sub by sub from the dictionary."""
    od = srv.face.od(srv.model)
    count = od.peek(index, 0)
    return struct.pack(f"<BB{count}{fmt}", count, 0,
                       *(od.peek(index, s) for s in range(1, count + 1)))


@pytest.mark.parametrize(("index", "fmt"), [
    (0x1C12, U16), (0x1C13, U16), (0x1600, U32), (0x1A00, U32), (0x1AFF, U32),
    (0xF030, U32), (0xF050, U32)])
def test_pdo_objects_uploaded_by_complete_access(preop, index, fmt):
    srv = trscat(preop)
    assert ca_upload(srv, index) == whole(srv, index, fmt)


def test_0x1c00_is_answered_by_the_wire(preop):
    """SOEM's ecx_readPDOmapCA reads 0x1C00 first, by complete access (docs/ethercat-wire.md)."""
    assert ca_upload(trscat(preop), 0x1C00) == bytes.fromhex("04 00 01 02 03 04")


def test_a_mapping_larger_than_the_mailbox_is_segmented(preop):
    srv = trscat(preop, mailbox_size=32)
    assert ca_upload(srv, 0x1600) == whole(srv, 0x1600, U32)


def test_0xf030_written_whole_in_preop_changes_the_pdo_assignment(preop):
    """§9.3.2: the master writes the slot list in PRE-OP; 0x1C12 follows. The expansion left
    out: one slot, the integrated module's RxPDO only; then put back."""
    srv = trscat(preop)
    ca_download(srv, 0xF030, 0, struct.pack("<BBI", 1, 0, IO_B))
    assert ca_upload(srv, 0x1C12) == struct.pack("<BBH", 1, 0, 0x1600)
    ca_download(srv, 0xF030, 0, struct.pack("<BBII", 2, 0, IO_B, IO_E))
    assert ca_upload(srv, 0x1C12) == struct.pack("<BBHH", 2, 0, 0x1600, 0x1601)


def test_0xf030_refused_outside_preop_with_0x08000022():
    srv = trscat(line_rig("SAFEOP"))
    assert srv.model.al_state is AlState.SAFEOP
    before = ca_upload(srv, 0xF030)
    code = abort_of(ca_download, srv, 0xF030, 0, struct.pack("<BBI", 1, 0, IO_B))
    assert code == AbortCode.CANNOT_STORE_STATE
    assert ca_upload(srv, 0xF030) == before


def test_0xf030_with_a_bad_ident_midway_is_left_as_it_was(preop):
    """Sub 3 holds an ident §9.3.2 does not allow: 0x06090030 on sub 3 after subs 0-2 went
    through the model; they are written back, so 0xF030 and the assignment are unchanged."""
    srv = trscat(preop)
    before = [ca_upload(srv, i) for i in (0xF030, 0x1C12, 0x1C13)]
    data = struct.pack("<BBIII", 3, 0, IO_B, IO_E, 0x12345678)
    assert abort_of(ca_download, srv, 0xF030, 0, data) == AbortCode.VALUE_RANGE
    assert [ca_upload(srv, i) for i in (0xF030, 0x1C12, 0x1C13)] == before


def test_a_complete_access_from_sub_2_is_refused(preop):
    request = bytes.fromhex("0a 00 00 00 00 13 00 20 50 30 f0 02 00 00 00 00")
    (reply,) = trscat(preop).handle(request)
    assert reply[8:].hex(" ") == "80 30 f0 02 00 00 01 06"


def test_only_the_trscat_announces_it_in_sii_and_esi(tmp_path):
    rig = line_rig("PREOP")
    descs = esi.rig_descriptions(rig)
    flags = {d.device_id: bool(d.coe_details & COE_COMPLETE_ACCESS) for d in descs}
    assert flags == {"fastcat": False, "trscat": True, "cpx": False, "drive_ecat-ecat": False}
    for path in esi.write(descs, tmp_path):
        coe = path.read_text()
        assert ('CompleteAccess="true"' in coe) == ("TRS-CAT" in path.name), path.name


@pytest.mark.parametrize("device", ["fastcat", "cpx", "drive_ecat-ecat"])
def test_the_other_slaves_refuse_it(device):
    """Seeds 000, 002 and 004 name no complete access: abort 0x06010000, as before."""
    rig = line_rig("PREOP")
    model = rig.devices[device]
    srv = CoeServer(face_for(model), model)
    assert abort_of(ca_upload, srv, 0x1018) == AbortCode.UNSUPPORTED_ACCESS
