"""0x1A40 "Diag History – TxPDO" on the wire (seed 002 l. 539-541, Tab. 27 l. 674-675): the
ESI offers it unassigned, a master assigns it with SDO downloads to 0x1C13 in PREOP, and the
SM3 image then carries 0x10F3:4 New Message Available, which follows the history."""

from __future__ import annotations

import pytest
from test_faces import line_rig

from app.ethercat_wire.faces import face_for
from devices.cpx.assignment import DIAG_PDO, TX_ASSIGN
from devices.od import AbortCode, SdoAbort


def test_0x1a40_assigned_over_sdo_carries_new_message_available():
    rig = line_rig("PREOP", cpx_dil=(True, False))  # STI: CPX errors go to 0x10F3
    cpx = rig.devices["cpx"]
    face = face_for(cpx)
    desc = face.describe(cpx)
    assert DIAG_PDO in [p.index for p in desc.spare_tx_pdos]
    assert DIAG_PDO not in [p.index for p in desc.tx_pdos]
    before = len(face.inputs(cpx))
    tx = list(face.tx_pdos(cpx))
    face.download_raw(cpx, TX_ASSIGN, 0, b"\x00")
    for sub, pdo in enumerate([*(p.index for p in tx), DIAG_PDO], start=1):
        face.download_raw(cpx, TX_ASSIGN, sub, pdo.to_bytes(2, "little"))
    face.download_raw(cpx, TX_ASSIGN, 0, bytes([len(tx) + 1]))
    assert [p.index for p in face.tx_pdos(cpx)][-1] == DIAG_PDO
    assert face.describe(cpx).spare_tx_pdos == ()
    bits = sum(e.bits for p in tx for e in p.entries)
    assert len(face.inputs(cpx)) == before + 1 == bits // 8 + 1

    def flag() -> int:
        return face.inputs(cpx)[bits // 8] & 1

    assert flag() == 0
    cpx.apply("inject_fault", {"fault": "module_failure"}, 1)  # CPX error 129, module 1
    rig.run_until(rig.clock.now_us + 50_000)
    assert cpx.history.count and flag() == 1  # a new message logged
    newest = cpx.history.newest
    face.upload_raw(cpx, 0x10F3, newest)  # Overwrite mode: reading the newest lowers it
    assert flag() == 0
    with pytest.raises(SdoAbort) as exc:
        face.download_raw(cpx, TX_ASSIGN, 0, b"\x00")
        face.download_raw(cpx, TX_ASSIGN, 1, (0x1A41).to_bytes(2, "little"))
    assert exc.value.code == AbortCode.VALUE_RANGE


def test_sii_and_esi_announce_pdo_assignment():
    """0x1C13 is writable, so the SII GENERAL CoE byte has PDO Assign (0x04) and the ESI says
    PdoAssign="true": a configurator that trusts the ESI assigns 0x1A40. Before: 0x03 / false.
    The shipped static/esi file is checked against a fresh export by test_sii_esi.py."""
    import xml.etree.ElementTree as ET

    from app.ethercat_wire import esi, sii
    from app.ethercat_wire.faces.base import COE_PDO_ASSIGN

    cpx = line_rig("PREOP").devices["cpx"]
    desc = face_for(cpx).describe(cpx)
    assert desc.coe_details & COE_PDO_ASSIGN
    general = sii.categories(sii.build(desc))[sii.CAT_GENERAL][0]
    assert general[5] & COE_PDO_ASSIGN
    coe = ET.fromstring(ET.tostring(esi.document(desc).getroot())).find(".//Mailbox/CoE")
    assert coe is not None and coe.get("PdoAssign") == "true"
    assert coe.get("PdoConfig") == "false"  # the mappings stay fixed (Tab. 27 sub 0 RO)


def test_0x1a40_first_is_refused_and_last_keeps_every_module_byte():
    """Seed 002 §2.3.1 / Tab. 9: module data at byte addresses. 0x1A40 (one bit, Tab. 27) is
    accepted only after the module TxPDOs: the SM3 bytes before it are those of the default
    assignment, and the bit sits in a byte of its own (7 bits unused)."""
    rig = line_rig("PREOP", cpx_dil=(True, False))
    cpx = rig.devices["cpx"]
    face = face_for(cpx)
    tx = [p.index for p in face.tx_pdos(cpx)]
    before = face.inputs(cpx)

    def write(pdos: list[int]) -> None:
        face.download_raw(cpx, TX_ASSIGN, 0, b"\x00")
        for sub, pdo in enumerate(pdos, start=1):
            face.download_raw(cpx, TX_ASSIGN, sub, pdo.to_bytes(2, "little"))
        face.download_raw(cpx, TX_ASSIGN, 0, bytes([len(pdos)]))

    with pytest.raises(SdoAbort) as exc:
        write([DIAG_PDO, *tx])
    assert exc.value.code == AbortCode.VALUE_RANGE
    write([*tx, DIAG_PDO])
    after = face.inputs(cpx)
    assert after[:len(before)] == before and len(after) == len(before) + 1
    assert after[-1] & 0xFE == 0
