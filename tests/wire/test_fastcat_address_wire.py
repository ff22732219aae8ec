"""The FastCAT's address check (seed 000 §6.19, 0x5301; §7.5 0x12) against a master on the wire.

§6.19: «Il master ethercat assegna un indirizzo logico ad ogni nodo rilevato lungo la linea ...
Nel master va assegnato manualmente lo stesso indirizzo logico»; at the transition to OP, with
0x5301 = 1, the rotary switch is compared with «l'indirizzo logico assegnato dal master
Ethercat», else CO_E_ADDRESS_MASTER_NOT_OK (0x5400 = 0x12000000). The address a master assigns
each slave on the line is the configured station address, ESC register 0x0010 (ETG.1000.4;
TwinCAT's "EtherCAT Addr"), compared whole (docs/fastcat-coupler.md "Address check"). Before,
the rig file's ``master_address`` decided with a wire master too, whatever it wrote at 0x0010.
"""

from __future__ import annotations

import struct
from typing import Any

import pytest
from test_bridge import FakeB, bridged, sdo_upload, sim
from test_esc import make_line, one
from test_faces import line_rig

from app.ethercat_wire import messages as msg
from app.ethercat_wire import registers as R
from app.ethercat_wire.datagrams import Cmd
from app.player import reset_in_place

FASTCAT = 0  # line position (wire_line.LINE)
EMERGENCY_0x12 = "00 ff 81 00 00 00 12 00"  # FF00, 0x81, 0x5400 = 0x12000000 (§6.19, §7.5)


def sdo_download_u8(index: int, sub: int, value: int, counter: int = 1) -> bytes:
    """An expedited one-byte SDO download as SOEM writes it (command 0x2F)."""
    body = struct.pack("<HBHB", 2 << 12, 0x2F, index, sub) + bytes((value, 0, 0, 0))
    return struct.pack("<HHBB", len(body), 0, 0, 3 | counter << 4) + body


def enable_check_and_request_op(b: FakeB) -> None:
    """What a master's start-up and state change do: 0x5301 = 1 in PRE-OP, SAFE-OP, OP."""
    b.send(msg.MAILBOX, FASTCAT, sdo_download_u8(0x5301, 0, 1))
    reply = b.expect(lambda m: m[:2] == (msg.MAILBOX_REPLY, FASTCAT)
                     and m[2][6:8] == b"\x00\x30")[2]
    assert reply[8] == 0x60  # download response, no abort
    b.send(msg.AL_CONTROL, FASTCAT, 0x04)
    b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x04, 0))
    b.send(msg.AL_CONTROL, FASTCAT, 0x08)


def wire_at_preop(rotary: int) -> Any:
    """The line rig in PRE-OP, the FastCAT's switch at ``rotary`` (the built-in master's
    ``master_address`` is 1), behind a bridge whose process B the test plays."""
    return bridged(line_rig("PREOP", fastcat_rotary=rotary))


# ---- process B: the master's write reaches A ----------------------------------------------
def test_a_masters_write_to_the_station_address_goes_to_process_a():
    line, outbox, _ = make_line(2)
    one(line, Cmd.APWR, -1, R.STATION_ADDRESS, struct.pack("<H", 1002))
    assert outbox == [(msg.STATION, 1, 1002)]
    outbox.clear()
    one(line, Cmd.APWR, -1, R.STATION_ADDRESS, struct.pack("<H", 1002))  # the same again
    assert outbox == []
    one(line, Cmd.FPWR, 1002, R.STATION_ADDRESS, struct.pack("<H", 3))  # TwinCAT's own value
    assert outbox == [(msg.STATION, 1, 3)]
    assert one(line, Cmd.FPRD, 3, R.STATION_ADDRESS, b"\0\0").data == b"\x03\x00"


# ---- process A: the coupler compares what the wire master wrote ----------------------------
def test_station_address_equal_to_the_rotary_switch_reaches_op():
    """Rotary 3, the wire master's 0x0010 = 3: OP, whatever the rig file's master_address
    (1, the built-in master's) says."""
    with wire_at_preop(rotary=3) as (runtime, _bridge, b):
        b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x02, 0))
        b.send(msg.STATION, FASTCAT, 3)
        enable_check_and_request_op(b)
        b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x08, 0))
        fastcat = runtime.rig.devices["fastcat"]
        assert sim(runtime, lambda: fastcat.alarm) is None


@pytest.mark.parametrize(("rotary", "station"), [
    (1, 1001),  # TwinCAT's default EtherCAT Addr of the first box (§7.1 '(1001)')
    (1, 0x1001),  # SOEM's config_init
    (3, 0x0103),  # the low byte alone is not the address
])
def test_station_address_other_than_the_rotary_switch_raises_0x12(rotary: int, station: int):
    """The rig file's master_address equals the switch (1) or not: the wire master's 0x0010
    decides. §6.19: CO_E_ADDRESS_MASTER_NOT_OK, 0x5400 = 0x12000000 in the emergency, the ESM
    back in PRE-OP with 0x8012 (§7.7)."""
    with wire_at_preop(rotary=rotary) as (runtime, _bridge, b):
        b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x02, 0))
        b.send(msg.STATION, FASTCAT, station)
        enable_check_and_request_op(b)
        b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x12, 0x8012))
        reply = b.expect(lambda m: m[:2] == (msg.MAILBOX_REPLY, FASTCAT)
                         and m[2][6:8] == b"\x00\x10")
        assert reply[2][8:].hex(" ") == EMERGENCY_0x12
        fastcat = runtime.rig.devices["fastcat"]
        assert sim(runtime, lambda: fastcat.od.peek(0x5400, 0)) == 0x1200_0000


def test_a_load_keeps_the_address_the_wire_master_wrote():
    """A scenario load resets the models in place; B's ESC keeps its 0x0010 (no slave was
    switched off), so the fresh coupler compares the same address."""
    with wire_at_preop(rotary=3) as (runtime, _bridge, b):
        b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x02, 0))
        b.send(msg.STATION, FASTCAT, 3)
        b.send(msg.MAILBOX, FASTCAT, sdo_upload(0x5302, 0))  # answered: the station was taken
        b.expect(lambda m: m[:2] == (msg.MAILBOX_REPLY, FASTCAT) and m[2][6:8] == b"\x00\x30")
        fastcat = runtime.rig.devices["fastcat"]
        sim(runtime, lambda: reset_in_place(runtime.rig, line_rig("PREOP", fastcat_rotary=3)))
        b.send(msg.AL_CONTROL, FASTCAT, 0x02)
        enable_check_and_request_op(b)
        b.expect(lambda m: m == (msg.AL_STATUS, FASTCAT, 0x08, 0))
        assert sim(runtime, lambda: fastcat.alarm) is None
