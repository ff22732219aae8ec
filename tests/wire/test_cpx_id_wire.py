"""The CPX-E-EC's Explicit Device ID on the wire (seed 002 Tab. 5 l. 253, §2.1 l. 173 "Hot
Connect"; ETG.1020 "Requesting ID mechanism"): the configured station alias at 0x0012 and in
SII word 4 (with the CRC of words 0-6), and a master's AL control with the ID request bit
(0x20) answered with AL status bit 0x20 and the ID at 0x0134, through the bridge and the
emulated ESC as a SOEM-like master reads them."""

from __future__ import annotations

import struct

import pytest
from test_bridge import bridged, sim
from test_esc import one
from test_faces import line_rig

from app.ethercat_wire import messages as msg
from app.ethercat_wire import registers as R
from app.ethercat_wire import sii
from app.ethercat_wire.datagrams import Cmd
from app.ethercat_wire.faces import face_for
from app.ethercat_wire.wire_process import apply_message, build_line

CPX = 2  # line position (wire_line.LINE)
ID = 0x123


def alias_of(line, position: int = 0) -> tuple[int, int]:
    """0x0012 as a master reads it (APRD) and SII word 4 with its checksum checked."""
    reg = struct.unpack("<H", one(line, Cmd.APRD, -position, R.STATION_ALIAS, b"\0\0").data)[0]
    image = bytes(line.escs[position].sii)
    assert image[14] == sii.crc8(image[:14])
    return reg, struct.unpack_from("<H", image, 8)[0]


def test_station_alias_is_the_explicit_device_id_in_force():
    rig = line_rig("PREOP", cpx_rotary=ID)
    model = rig.devices["cpx"]
    line = build_line([face_for(model).describe(model)], [])
    assert alias_of(line) == (ID, ID)
    apply_message(line, (msg.ALIAS, 0, 0xFFF))  # after a restart with the switches moved
    assert alias_of(line) == (0xFFF, 0xFFF)


@pytest.fixture
def wire():
    with bridged(line_rig("PREOP", cpx_rotary=ID)) as wired:
        yield wired


def test_id_request_through_the_bridge(wire):
    runtime, _bridge, b = wire
    assert b.descriptions[CPX].station_alias == ID
    b.expect(lambda m: m == (msg.AL_STATUS, CPX, 0x02, 0))
    b.send(msg.AL_CONTROL, CPX, 0x22)  # PREOP + ID request
    b.expect(lambda m: m == (msg.AL_STATUS, CPX, 0x22, ID))
    b.send(msg.AL_CONTROL, CPX, 0x02)  # without the bit: the AL status code is back
    b.expect(lambda m: m == (msg.AL_STATUS, CPX, 0x02, 0))
    model = runtime.rig.devices["cpx"]
    sim(runtime, lambda: model.apply("set_rotary", {"value": 0x456}, None))
    sim(runtime, lambda: model.apply("restart", {}, None))
    b.expect(lambda m: m == (msg.ALIAS, CPX, 0x456))
    # Tab. 5: at 0 the stored address stays: "no ID" (None), at every start (an ESC reloads
    # 0x0012 from SII word 4 at power-up), even when nothing else changed
    sim(runtime, lambda: model.apply("set_rotary", {"value": 0}, None))
    sim(runtime, lambda: model.apply("restart", {}, None))
    b.expect(lambda m: m == (msg.ALIAS, CPX, None))
    sim(runtime, lambda: model.apply("restart", {}, None))
    b.expect(lambda m: m == (msg.ALIAS, CPX, None))


def test_switch_at_zero_keeps_the_stored_alias():
    """Tab. 5 l. 253 «0 = сохраненный адрес EtherCAT»: a restart with the switches at 0 leaves
    SII word 4 as stored (here by a master's alias tool) and loads 0x0012 from it; before, it
    wrote 0 over both."""
    rig = line_rig("PREOP", cpx_rotary=0)
    model = rig.devices["cpx"]
    desc = face_for(model).describe(model)
    assert desc.station_alias is None
    line = build_line([desc], [])
    assert alias_of(line) == (0, 0)  # a fresh EEPROM stores no alias
    sii.set_alias(line.escs[0].sii, 0x077)  # `ethercat alias -p 0 0x77` (word 4 + CRC)
    assert alias_of(line) == (0, 0x077)  # the ESC loads 0x0012 at power-up only
    apply_message(line, (msg.ALIAS, 0, None))  # the CPX restarted, switches at 0
    assert alias_of(line) == (0x077, 0x077)
    apply_message(line, (msg.ALIAS, 0, ID))  # a restart with the switches at 0x123
    assert alias_of(line) == (ID, ID)


def test_the_esc_forwards_the_raw_al_control_and_shows_the_answer():
    """B's side: the ESC hands the whole AL control word to A and shows A's AL status."""
    rig = line_rig("PREOP", cpx_rotary=ID)
    model = rig.devices["cpx"]
    outbox: list[tuple] = []
    line = build_line([face_for(model).describe(model)], outbox)
    one(line, Cmd.APWR, 0, R.AL_CONTROL, struct.pack("<H", 0x22))
    assert (msg.AL_CONTROL, 0, 0x22) in outbox
    apply_message(line, (msg.AL_STATUS, 0, 0x22, ID))
    status, _, code = struct.unpack("<HHH", one(line, Cmd.APRD, 0, R.AL_STATUS, bytes(6)).data)
    assert (status, code) == (0x22, ID)
