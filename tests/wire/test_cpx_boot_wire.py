"""The CPX-E-EC in BOOT on the wire: only the bootstrap mailbox runs, and it carries no CoE.

Seed 002 Tab. 11 (l. 373): Run flickering green, «Bootstrap (начальная загрузка) Шинный модуль
получает обновление встроенного ПО» — in BOOT the bus module receives a firmware update.
ETG.1000.6: in BOOT only the bootstrap mailbox is served, for the firmware download (FoE); a
CoE request gets a mailbox error "unsupported protocol" (0x0002), as the ETG sample stack
answers a non-FoE message in boot mode (docs/cpx-e-ec.md choice 47).
"""

from __future__ import annotations

import pytest
from test_coe import hexes, mbx
from test_faces import line_rig

from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.faces import face_for
from devices.ethercat import AlState
from devices.od import AbortCode, SdoAbort

UPLOAD_1018_2 = "00 20 40 18 10 02 00 00 00 00"  # SDO upload 0x1018:2
UNSUPPORTED_PROTOCOL = "04 00 00 00 00 {c}0 01 00 02 00"  # mailbox error, detail 0x0002


@pytest.fixture()
def boot():
    rig = line_rig("PREOP")
    rig.devices["master"].set_external(True)  # the wire master's AL control alone
    model = rig.devices["cpx"]
    face = face_for(model)
    face.request_state(model, AlState.INIT)
    face.request_state(model, AlState.BOOT)
    assert model.al_state is AlState.BOOT
    return rig, model, face


def test_coe_in_boot_gets_a_mailbox_error(boot):
    _rig, model, face = boot
    srv = CoeServer(face, model)
    assert hexes(srv.handle(mbx(UPLOAD_1018_2))) == [UNSUPPORTED_PROTOCOL.format(c=1)]
    # SDO information is CoE too
    assert hexes(srv.handle(mbx("00 80 01 00 00 00 01 00", counter=2))) == [
        UNSUPPORTED_PROTOCOL.format(c=2)]


def test_coe_answers_again_after_boot(boot):
    _rig, model, face = boot
    face.request_state(model, AlState.INIT)
    face.request_state(model, AlState.PREOP)
    assert model.al_state is AlState.PREOP
    (reply,) = CoeServer(face, model).handle(mbx(UPLOAD_1018_2))
    assert reply[8] == 0x43  # expedited upload, the identity's product code
    assert int.from_bytes(reply[12:16], "little") == face.od(model).peek(0x1018, 2)


def test_no_emergency_leaves_in_boot(boot):
    """Emergencies are CoE (service 1): one queued before BOOT waits in the model."""
    _rig, model, face = boot
    model.diagnosis.mailbox = [bytes(8)]
    assert face.take_emergencies(model) == []
    assert model.diagnosis.mailbox == [bytes(8)]


def test_the_built_in_masters_sdo_gets_no_answer_in_boot(boot):
    """The built-in master's SDO (devices/esm.py CoeMailbox) times out as in INIT."""
    _rig, model, _face = boot
    with pytest.raises(SdoAbort) as err:
        model.sdo_upload(0x1018, 2)
    assert err.value.code == AbortCode.SDO_TIMEOUT
