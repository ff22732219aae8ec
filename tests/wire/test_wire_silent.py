"""A slave that is powered but does not answer (the drive with c9 != 11 at power-up, seed 004
ch. 2; docs/ethercat-coe.md "How it runs") on the wire: its ESC passes the frames on, as the
built-in master's line has it (devices/master/line.py ``frame_path``), so the slaves behind
it answer and damaged cables behind it spoil frames; it takes no datagram itself
(docs/ethercat-wire.md "Silent slaves"). The frames that cross it reach its model, whose L/A
LEDs (the ESC's, ETG.1300) flicker with them as with the built-in master (docs/ethercat-coe.md
"LEDs of a drive with c9 != 11")."""

from __future__ import annotations

import struct
import time

import pytest
from test_bridge import WAIT_S, bridged, sim
from test_esc import make_line, one
from test_wire_damage import damage, frame

from app.ethercat_wire import messages as msg
from app.ethercat_wire import registers as R
from app.ethercat_wire.datagrams import Cmd
from app.ethercat_wire.wire_process import apply_message, build_line, cycle_counts
from app.rig_config import build_rig, parse_rig_spec

SILENT_DRIVE_FIRST = """
[rig]
name = "silent drive first"
seed = 1
step_ms = 1
[master]
line = ["drive_ec-ecat", "fastcat"]
[[servo]]
id = "drive_ec"
fieldbus = "ethercat"
node_id = 3
parameters = { c9 = 3 }
[[fastcat]]
id = "fastcat"
modules = ["DI16"]
"""


def test_a_silent_slave_passes_frames_on_and_takes_no_datagram():
    line, _, _ = make_line(3)
    assert apply_message(line, (msg.SILENT, 0, True))
    reply = one(line, Cmd.BRD, 0, R.TYPE, b"\0\0")
    assert (reply.wkc, reply.adp) == (2, 2)  # the two behind it answer, it counts nothing
    assert one(line, Cmd.APWR, 0, R.STATION_ADDRESS, b"\x01\x10").wkc == 1
    assert [esc.station for esc in line.escs] == [0, 0x1001, 0]  # position 0 of the answers
    apply_message(line, (msg.SILENT, 0, False))
    assert one(line, Cmd.BRD, 0, R.TYPE, b"\0\0").wkc == 3


def test_a_silent_last_slave_leaves_port_1_of_the_one_before_it_open():
    """DL status is physical: the silent slave's PHY has link."""
    line, _, _ = make_line(3)
    apply_message(line, (msg.SILENT, 2, True))
    status = struct.unpack("<H", one(line, Cmd.APRD, -1, R.DL_STATUS, b"\0\0").data)[0]
    assert status & 0x0C00 == 0x0800  # port 1 open and communicating


def test_only_silent_slaves_on_the_path_return_the_frame_unanswered():
    """Link on the master's port and nobody answers: the frame comes back, working counter 0
    (the built-in master's phase no_answer), not dropped as with the link down."""
    line, _, _ = make_line(1)
    apply_message(line, (msg.SILENT, 0, True))
    assert one(line, Cmd.BRD, 0, R.TYPE, b"\0\0").wkc == 0
    apply_message(line, (msg.LINK, 0, False))
    assert not line.process(frame())


def test_a_damaged_cable_behind_a_silent_slave_spoils_the_frames():
    line, _, _ = make_line(2)
    apply_message(line, (msg.SILENT, 0, True))
    damage(line, {1: 1.0})
    assert not line.process(frame())
    assert line.spoiled == 1


def test_the_frames_crossing_a_silent_slave_are_counted_for_it():
    """Its ESC forwards every frame, process data or not (a BRD here), from the moment it is
    silent; frames lost to a damaged cable before it, or that stop before it, do not cross it."""
    line, _, _ = make_line(3)
    line.process(frame())  # before it went silent: it answered this one
    apply_message(line, (msg.SILENT, 1, True))
    for _ in range(4):
        line.process(frame())
    assert cycle_counts(line) == {1: 4}
    assert cycle_counts(line) == {}  # taken
    damage(line, {0: 1.0})  # every frame spoiled on cable 0, before it
    assert not line.process(frame())
    damage(line, {})
    line.process(frame())
    apply_message(line, (msg.LINK, 1, False))  # its cable pulled: the frames stop before it
    line.process(frame())
    assert cycle_counts(line) == {1: 1}
    apply_message(line, (msg.LINK, 0, True))
    apply_message(line, (msg.SILENT, 1, False))  # it answers again: its exchanges only
    line.process(frame())
    assert cycle_counts(line) == {}


@pytest.fixture
def silent_first():
    rig = build_rig(parse_rig_spec(SILENT_DRIVE_FIRST))
    rig.run_until(4_000_000)  # the FastCAT in OP behind the silent drive (built-in master)
    with bridged(rig) as wired:
        yield wired


def test_the_bridge_keeps_the_slaves_behind_a_silent_one_on_the_wire(silent_first):
    runtime, _bridge, b = silent_first
    b.expect(lambda m: m == (msg.SILENT, 0, True))
    sim(runtime, lambda: None)  # a step or more later: nothing cut the line
    assert not [m for m in b.seen if m[0] == msg.LINK and not m[2]]
    runtime.command("master", "pull_cable", {"cable": 1}).result(timeout=WAIT_S)
    b.expect(lambda m: m == (msg.LINK, 1, False))  # the FastCAT's own cable: from 1 on


def _drive_leds(runtime) -> dict[str, str]:
    return sim(runtime, lambda: runtime.rig.devices["drive_ec"].snapshot()["leds"])


def _until(check, seconds: float = WAIT_S, between=lambda: time.sleep(0.01)) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if check():
            return True
        between()
    return False


def test_the_wire_masters_frames_flicker_a_silent_drives_l_a(silent_first):
    """The frames cross B's silent ESC, B counts them for it, the bridge hands them to the
    drive: its L/A flicker as with the built-in master, Status and Error stay dark. Until
    session 20 the wire's counts reached exchange_frame only, which the drive ignores: its L/A
    stayed on (link, no traffic)."""
    runtime, bridge, b = silent_first
    b.expect(lambda m: m == (msg.SILENT, 0, True))
    line = build_line(bridge.descriptions, [])
    apply_message(line, (msg.SILENT, 0, True))
    # The built-in master's last frames are older than the 50 ms activity window
    assert _until(lambda: _drive_leds(runtime)["L/A IN"] == "on")

    def master_cycles() -> None:  # 10 frames of a 1 ms cycle, reported as B does
        for _ in range(10):
            line.process(frame())
        b.send(msg.CYCLE, cycle_counts(line))
        time.sleep(msg.CYCLE_REPORT_S)

    # the batches reach the drive at A's steps: on a loaded machine after a while
    assert _until(lambda: _drive_leds(runtime) == {
        "L/A IN": "flickering", "Status": "off", "L/A OUT": "flickering", "Error": "off"},
        WAIT_S, master_cycles)
