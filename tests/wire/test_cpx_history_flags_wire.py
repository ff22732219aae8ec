"""A master on the wire that writes no 0x10F3:5 finds Tab. 14's 0x0000 (seed 002), whatever the
rig file's ``history_flags`` says: that value is the built-in master's start-up write
(docs/cpx-e-ec.md choice 19). Before, the model powered up with it, so TwinCAT or SOEM saw
emergencies on from power-up, and again after every power cycle with no write at all."""

from __future__ import annotations

from test_coe import mbx
from wire_line import line_spec

from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.faces import face_for
from app.rig_config import build_rig, parse_rig_spec
from devices.ethercat import AlState


def _upload_flags(srv: CoeServer) -> int:
    (reply,) = srv.handle(mbx("00 20 40 f3 10 05 00 00 00 00"))  # upload 0x10F3:5
    assert reply[8] & 0x43 == 0x43, reply.hex(" ")  # expedited
    return int.from_bytes(reply[12:14], "little")


def test_a_wire_master_finds_emergencies_off() -> None:
    text = line_spec(cpx_dil=(True, False)).replace("rotary_switch = 0\n",
                                                     "rotary_switch = 0\nhistory_flags = 1\n")
    rig = build_rig(parse_rig_spec(text, "wire.toml"))
    rig.devices["master"].set_external(True)  # as --ethercat-if: the wire's master runs it
    cpx = rig.devices["cpx"]
    srv = CoeServer(face_for(cpx), cpx)
    cpx.request_state(AlState.PREOP)
    rig.run_until(100_000)
    assert cpx.al_state is AlState.PREOP
    assert _upload_flags(srv) == 0x0000
    cpx.take_emergencies()
    rig.apply("cpx/1", "short_circuit", {"on": True})
    rig.run_until(rig.clock.now_us + 100_000)
    assert cpx.take_emergencies() == []  # stored in 0x10F3 only
    rig.apply("cpx/1", "short_circuit", {"on": False})
    assert srv.handle(mbx("00 20 2b f3 10 05 01 00 00 00"))[0][8] == 0x60  # the wire's write
    assert _upload_flags(srv) == 0x0001
    rig.apply("cpx", "restart", {})
    rig.run_until(rig.clock.now_us + 10_000)
    cpx.request_state(AlState.PREOP)
    rig.run_until(rig.clock.now_us + 100_000)
    assert _upload_flags(srv) == 0x0000  # a restart: Tab. 14's default again
