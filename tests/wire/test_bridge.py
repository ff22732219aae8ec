"""The bridge in process A with a fake process B: the test holds B's end of the pipe.

Messages are the wire contract's (app/ethercat_wire/messages.py); the rig runs in a live
runtime, so every model access goes through the simulation thread as in the app. Checked:
descriptions handed to B, the built-in master switched to external mode, AL control answered
with the model's AL status, SDO over the mailbox, outputs reaching the model, frames and
statistics reaching the master panel, a pulled cable as ``link``, the FastCAT emergency of
seed 000 §7.1 as a CoE mailbox message, and ``stop``.
"""

from __future__ import annotations

import contextlib
import struct
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from test_faces import line_rig
from wire_line import LINE, line_spec

from app.ethercat_wire import faces
from app.ethercat_wire import messages as msg
from app.ethercat_wire.bridge import WireBridge
from app.ethercat_wire.frame_clock import FrameClock
from app.ethercat_wire.launch import check_interface
from app.player import reset_in_place
from app.rig_config import RigConfigError, build_rig, parse_rig_spec
from app.runtime import Runtime

WAIT_S = 10.0


class FakeB:
    """Process B reduced to its end of the pipe."""

    def __init__(self) -> None:
        self.conn: Any = None
        self.descriptions: list[Any] = []
        self.seen: list[tuple[Any, ...]] = []

    def spawn(self, iface: str, descriptions: Any, conn: Any) -> FakeB:
        self.conn, self.descriptions = conn, list(descriptions)
        conn.send((msg.READY, iface))
        return self

    def is_alive(self) -> bool:
        return False

    def join(self, timeout: float | None = None) -> None:
        return None

    def send(self, *message: Any) -> None:
        self.conn.send(message)

    def expect(self, wanted: Callable[[tuple[Any, ...]], bool]) -> tuple[Any, ...]:
        """The first message (new or already seen) that ``wanted`` accepts."""
        for message in self.seen:
            if wanted(message):
                self.seen.remove(message)
                return message
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            if self.conn.poll(0.01):
                message = self.conn.recv()
                if wanted(message):
                    return message
                self.seen.append(message)
        raise AssertionError(f"no such message; seen: {self.seen[-10:]}")


@contextlib.contextmanager
def bridged(rig: Any) -> Iterator[tuple[Runtime, WireBridge, FakeB]]:
    """``rig`` run by a Runtime, its line behind a bridge whose process B is a :class:`FakeB`;
    both stopped on exit."""
    runtime = Runtime(rig)
    runtime.start()
    b = FakeB()
    bridge = WireBridge(runtime, "veth-test", spawn=b.spawn)
    bridge.start(timeout_s=WAIT_S)
    try:
        yield runtime, bridge, b
    finally:
        bridge.stop()
        runtime.stop()


def sdo_upload(index: int, sub: int, counter: int = 1) -> bytes:
    body = struct.pack("<HBHB", 2 << 12, 0x40, index, sub) + bytes(4)
    return struct.pack("<HHBB", len(body), 0, 0, 3 | counter << 4) + body


@pytest.fixture
def wire():
    with bridged(line_rig("OP")) as wired:
        yield wired


def sim(runtime: Runtime, fn: Callable[[], Any]) -> Any:
    return runtime.submit(fn).result(timeout=WAIT_S)


def master_view(runtime: Runtime) -> Any:
    return runtime.rig.devices["master"]


def test_start_describes_the_line_and_takes_over_from_the_built_in_master(wire):
    runtime, bridge, b = wire
    assert [d.device_id for d in b.descriptions] == list(LINE)
    assert [d.name for d in b.descriptions] == ["FastCAT", "TRS-CAT", "CPX-E-EC",
                                                "SelemaDriveECAT"]
    assert bridge.ready_iface == "veth-test"
    assert sim(runtime, lambda: master_view(runtime).external) is True
    for pos in range(len(LINE)):
        b.expect(lambda m, pos=pos: m[:2] == (msg.AL_STATUS, pos))
    b.send(msg.CYCLE, {pos: 3 for pos in range(len(LINE))})  # inputs go with the frames
    for pos in range(len(LINE)):
        b.expect(lambda m, pos=pos: m[:2] == (msg.INPUTS, pos))


def test_al_control_is_answered_with_the_models_al_status(wire):
    runtime, _bridge, b = wire
    b.expect(lambda m: m == (msg.AL_STATUS, 0, 8, 0))
    b.send(msg.AL_CONTROL, 0, 0x02)
    b.expect(lambda m: m == (msg.AL_STATUS, 0, 2, 0))
    assert sim(runtime, lambda: master_view(runtime).links[0].requested.name) == "PREOP"
    b.send(msg.AL_CONTROL, 2, 0x05)  # no such state: 0x0012 on the model's ESM
    b.expect(lambda m: m[:2] == (msg.AL_STATUS, 2) and m[3] == 0x0012)


def test_sdo_read_of_0x1018_on_every_slave(wire):
    runtime, _bridge, b = wire
    for pos, device in enumerate(LINE):
        b.send(msg.MAILBOX, pos, sdo_upload(0x1018, 2))
        reply = b.expect(lambda m, pos=pos: m[:2] == (msg.MAILBOX_REPLY, pos)
                         and m[2][6:8] == b"\x00\x30")[2]  # an SDO response, not an EMCY
        model = runtime.rig.devices[device]
        expected = sim(runtime, lambda model=model: model.od.peek(0x1018, 2))
        assert reply[8] == 0x43 and int.from_bytes(reply[12:16], "little") == expected


def test_outputs_reach_the_model(wire):
    """Seed 000 §6.28: DO16 (module 2) channel 1 = SM2 bit 8 (after 0x16FF's byte: the Reset
    fault bit 0 and §6.17's seven reserved bits)."""
    runtime, _bridge, b = wire
    b.send(msg.OUTPUTS, 0, (1 << 8).to_bytes(3, "little"))
    wait_for(lambda: runtime.frame.snapshot["devices"]["fastcat"]["rail"][1]["do"][0])


def wait_for(check: Callable[[], bool]) -> None:
    deadline = time.monotonic() + WAIT_S
    while not check():
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        time.sleep(0.02)


def test_frames_and_stats_reach_the_master(wire):
    """Frames reported by B reach each slave model through the master (external_frame)."""
    runtime, _bridge, b = wire
    drive = runtime.rig.devices["drive_ecat-ecat"]
    before = sim(runtime, lambda: (master_view(runtime).frames, drive.frames))
    b.send(msg.CYCLE, {pos: 3 for pos in range(len(LINE))})
    wait_for(lambda: sim(runtime, lambda: drive.frames) >= before[1] + 3)
    assert sim(runtime, lambda: master_view(runtime).frames) >= before[0] + 3 * len(LINE)
    b.send(msg.STATS, {"frames": 1234, "lrw": 1200, "cycle_us": 4000.0, "wkc_errors": 2,
                       "run": 0})
    wait_for(lambda: runtime.frame.snapshot["devices"]["master"]["stats"]["cycle_us"] == 4000)
    snap = runtime.frame.snapshot["devices"]["master"]
    assert snap["external"] is True
    assert snap["slaves"][0]["counters"]["wkc_errors"] == 2


def test_a_pulled_cable_takes_the_slaves_behind_it_off_the_wire(wire):
    runtime, _bridge, b = wire
    runtime.command("master", "pull_cable", {"cable": 2}).result(timeout=WAIT_S)
    b.expect(lambda m: m == (msg.LINK, 2, False))
    runtime.command("master", "plug_cable", {"cable": 2}).result(timeout=WAIT_S)
    b.expect(lambda m: m == (msg.LINK, 0, True))


def test_fastcat_emergency_reaches_the_mailbox(wire):
    """Seed 000 §7.1: module 2 stops answering -> FF00 / 81 / 02 00 00 04 00."""
    runtime, _bridge, b = wire
    runtime.command("fastcat/2", "module_failure", {"active": True}).result(timeout=WAIT_S)
    reply = b.expect(lambda m: m[:2] == (msg.MAILBOX_REPLY, 0) and m[2][6:8] == b"\x00\x10")
    assert reply[2][8:].hex(" ") == "00 ff 81 02 00 00 04 00"
    # the master panel counts and logs what the wire master received (external_emergency)
    wait_for(lambda: runtime.frame.snapshot["devices"]["master"]["slaves"][0]["counters"]
             ["emergencies"] >= 1)


def test_stop_tells_b_and_hands_the_line_back():
    runtime = Runtime(line_rig("OP"))
    runtime.start()
    b = FakeB()
    bridge = WireBridge(runtime, "veth-test", spawn=b.spawn)
    bridge.start(timeout_s=WAIT_S)
    bridge.stop()
    b.expect(lambda m: m == (msg.STOP,))
    wait_for(lambda: sim(runtime, lambda: master_view(runtime).external) is False)
    runtime.stop()


def test_a_missing_interface_is_a_clear_error():
    with pytest.raises(RigConfigError, match="no network interface 'fieldrig-nope0'"):
        check_interface("fieldrig-nope0")


def test_frames_go_to_the_models_one_master_cycle_apart():
    """3 frames reported over 12 ms of wall time: one every 4 ms of simulated time, not a
    burst (a burst leaves SYNC0 cycles without a frame, which the TRS-CAT counts as missed SM
    events, seed 001 §9.1.1), going on while the reports say the master cycles, none once they
    stop and the owed are out."""
    clock = FrameClock()
    clock.report(3, 0.012, now_us=100_000, wall=0.0)
    handed = [t for t in range(100_000, 120_000, 1_000) for _ in range(clock.due(t, 0.001))]
    assert handed == [100_000, 104_000, 108_000, 112_000, 116_000]
    assert clock.due(130_000, wall=1.0) == 0  # no report for a second: the master stopped


def test_dc_settings_are_kept_and_offered_to_the_model(wire):
    _runtime, bridge, b = wire
    settings = {"activation": 3, "sync0_cycle_ns": 4_000_000, "start_time_ns": 123}
    b.send(msg.DC, 1, settings)
    wait_for(lambda: bridge.dc.get(1) == settings)


# The TRS-CAT's (position 1) sync managers as a master sets them: SM2 as long as its outputs
# (2 bytes, the integrated module and a TRS-IO-E: 4, seed 001 §9.2 PS).
GOOD_SMS = ((0x1000, 128, 0x26, True), (0x1080, 128, 0x22, True), (0x1100, 4, 0x64, True),
            (0x1400, 6, 0x20, True))


def refused_for_a_short_sm2(b) -> None:
    """The TRS-CAT in PRE-OP with SAFE-OP refused for an SM2 one byte short: AL status 0x12,
    code 0x001D. PREOP goes with the ack: the line was in OP and without frames the TRS-CAT
    falls to SAFE-OP with the error flag (0x001A); a master acknowledges it as SOEM's
    config_init does."""
    b.send(msg.SM, 1, (*GOOD_SMS[:2], (0x1100, 3, 0x64, True), GOOD_SMS[3]))
    b.send(msg.AL_CONTROL, 1, 0x12)
    b.expect(lambda m: m[:2] == (msg.AL_STATUS, 1) and m[2] == 0x02)
    b.send(msg.AL_CONTROL, 1, 0x04)
    b.expect(lambda m: m == (msg.AL_STATUS, 1, 0x12, 0x001D))


def test_sm_registers_reach_the_model_which_checks_them(wire):
    """Seed 001 §9.2 PS: the TRS-CAT (position 1) refuses SAFE-OP when the SM2 the master
    wrote is not as long as its outputs (2 bytes, the integrated module and a TRS-IO-E: 4)."""
    _runtime, _bridge, b = wire
    refused_for_a_short_sm2(b)
    b.send(msg.SM, 1, GOOD_SMS)
    b.send(msg.AL_CONTROL, 1, 0x14)  # SAFE-OP + "Error Ind Ack" (EC_STATE_ACK)
    b.expect(lambda m: m == (msg.AL_STATUS, 1, 0x04, 0))


def test_a_request_over_the_error_flag_needs_the_ack_bit(wire):
    """AL control bit 4 reaches the model (ETG.1000.6 "Error Ind Ack", SSC AL_ControlInd):
    after a refused request the same request without it is ignored, with it it proceeds."""
    runtime, _bridge, b = wire
    trs = runtime.rig.devices["trscat"]
    refused_for_a_short_sm2(b)
    b.send(msg.SM, 1, GOOD_SMS)
    for request, state in ((0x02, "PREOP"), (0x04, "SAFEOP")):  # the current state, then on
        b.send(msg.AL_CONTROL, 1, request)
        wait_for(lambda state=state: sim(
            runtime, lambda: master_view(runtime).links[1].requested.name) == state)
        assert sim(runtime, lambda: (trs.al_status, trs.al_status_code)) == (0x12, 0x001D)
    b.send(msg.AL_CONTROL, 1, 0x14)
    b.expect(lambda m: m == (msg.AL_STATUS, 1, 0x04, 0))


def test_an_unknown_state_over_the_error_flag_needs_the_ack_bit(wire):
    """SSC AL_ControlInd / SOES ESC_state: over the error flag an unknown state code without
    bit 4 is ignored like any request but INIT, so the original code (0x001D) stays; with
    the bit it answers 0x0012 "Unknown requested state" (seed 000 §7.7)."""
    runtime, _bridge, b = wire
    trs = runtime.rig.devices["trscat"]
    refused_for_a_short_sm2(b)
    b.send(msg.AL_CONTROL, 1, 0x05)  # no such state, no ack: ignored
    b.send(msg.AL_CONTROL, 1, 0x02)  # taken in order: once the master notes it, 0x05 was
    wait_for(lambda: sim(runtime, lambda: master_view(runtime).links[1].requested.name)
             == "PREOP")
    assert sim(runtime, lambda: (trs.al_status, trs.al_status_code)) == (0x12, 0x001D)
    b.send(msg.AL_CONTROL, 1, 0x15)
    b.expect(lambda m: m == (msg.AL_STATUS, 1, 0x12, 0x0012))


def test_a_dead_wire_process_hands_the_line_back(wire):
    runtime, bridge, b = wire
    b.conn.close()  # process B gone: the pipe breaks
    wait_for(lambda: sim(runtime, lambda: master_view(runtime).external) is False)
    assert any("gone" in e for e in bridge.errors)


def test_b_s_cycle_measurement_is_taken_only_when_the_next_agrees():
    """The window the master started in reads long (25 ms at a 4 ms cycle): B's first
    measurement, and any far from the present period, counts only once the next agrees."""
    clock = FrameClock()
    clock.report(3, 0.012, now_us=0, wall=0.0)  # the rough estimate from A's reports
    clock.master_cycle(25_000.0)
    assert clock.period_us == 4_000 and not clock.measured
    clock.master_cycle(4_000.0)
    assert clock.period_us == 4_000 and not clock.measured  # 4 ms disagrees with 25 ms
    clock.master_cycle(4_010.0)
    assert (clock.period_us, clock.measured) == (4_010.0, True)
    clock.master_cycle(20_000.0)  # one window cut by a pause: not adopted
    assert clock.period_us == 4_010.0
    clock.master_cycle(4_000.0)
    assert clock.period_us == 4_000.0


def test_a_pause_between_two_long_measurements_keeps_the_period():
    """Two windows cut by a pause (no frames between them) must not agree on a long cycle."""
    clock = FrameClock()
    clock.master_cycle(4_000.0)
    clock.master_cycle(4_000.0)
    clock.master_cycle(20_000.0)
    clock.master_cycle(0.0)  # a window without frames: the master paused
    clock.master_cycle(20_000.0)
    assert clock.period_us == 4_000.0
    clock.master_cycle(20_000.0)  # two in a row with frames: the master now runs at 20 ms
    assert clock.period_us == 20_000.0


def test_the_models_esc_error_counters_reach_b_and_a_masters_write_clears_them(wire):
    """A pulled cable counts a lost link at both its ends (0x0310 + port); B gets the
    counters to answer reads of 0x0300-0x0313; a master's write there clears the model's."""
    runtime, _bridge, b = wire
    runtime.command("master", "pull_cable", {"cable": 2}).result(timeout=WAIT_S)
    counted = b.expect(lambda m: m[0] == msg.ESC_ERRORS and m[1] == 1 and any(m[2]))
    assert counted[2][0x10:0x12] == b"\x00\x01"  # port 1 (OUT) lost its link
    b.send(msg.ESC_ERRORS_WRITE, 1, 0x0310, 1, 1)
    b.expect(lambda m: m == (msg.ESC_ERRORS, 1, bytes(20), 1))
    assert sim(runtime, lambda: master_view(runtime).links[1].esc.lost_link) == [0] * 4


def test_a_masters_write_is_acknowledged_with_its_number_even_when_nothing_changes(wire):
    """B applies a write again on every answer of A's older than the write: A's answer to it
    carries its number (messages.py), so B stops, also when the counters were zero."""
    _runtime, _bridge, b = wire
    b.send(msg.ESC_ERRORS_WRITE, 0, 0x0300, 2, 7)
    b.expect(lambda m: m == (msg.ESC_ERRORS, 0, bytes(20), 7))


def test_a_rig_reset_in_place_brings_b_the_fresh_zero_counters(wire):
    """A scenario load resets the rig in place (app/player.py): the same device objects, so
    the bridge keeps its slaves and what it last sent B; the fresh master's zeros differ from
    the counted ones and reach B (B's ESC is not switched off by a reset)."""
    runtime, _bridge, b = wire
    runtime.command("master", "pull_cable", {"cable": 2}).result(timeout=WAIT_S)
    b.expect(lambda m: m[0] == msg.ESC_ERRORS and m[1] == 1 and any(m[2]))
    sim(runtime, lambda: reset_in_place(runtime.rig, line_rig("OP")))
    b.expect(lambda m: m[0] == msg.ESC_ERRORS and m[1] == 1 and not any(m[2]))


def test_after_a_load_at_0_s_the_bridge_keeps_its_timing_on_the_fresh_clock(wire):
    """A load puts the clock back to 0 s (app/player.py): the bridge's schedules start again
    with it, so the fresh model's ESC counters (and frames, inputs) do not wait for the
    simulated time the old run had reached (here over 3 s)."""
    runtime, _bridge, b = wire
    fresh = build_rig(parse_rig_spec(line_spec()))
    assert fresh.clock.now_us < 100_000 and \
        sim(runtime, lambda: runtime.rig.clock.now_us) > 2_000_000
    sim(runtime, lambda: reset_in_place(runtime.rig, fresh))
    runtime.command("master", "pull_cable", {"cable": 2}).result(timeout=WAIT_S)
    b.expect(lambda m: m[0] == msg.ESC_ERRORS and m[1] == 1 and any(m[2]))
    assert sim(runtime, lambda: runtime.rig.clock.now_us) < 1_000_000


def test_a_slave_s_own_pulled_out_cable_takes_the_slaves_behind_it_off_the_wire(wire):
    runtime, _bridge, b = wire
    runtime.command("trscat", "link", {"connected": False, "port": "out"}).result(timeout=WAIT_S)
    b.expect(lambda m: m == (msg.LINK, 2, False))
    runtime.command("trscat", "link", {"connected": True, "port": "out"}).result(timeout=WAIT_S)
    b.expect(lambda m: m == (msg.LINK, 0, True))


def test_a_module_alarm_keeps_op_and_the_wire_masters_reset_bit_clears_it(wire):
    """Seed 000 §7: Reset fault is "mappato nei dati scambiati con il coupler" (0x16FF bit 0
    of SM2) and Fault active is 0x1AFF bit 0 of SM3 (§5, §6.16, §6.17). A module alarm (§7.6)
    keeps OP with AL status code 0 (§7.7), so a wire master reads the fault and resets it
    through the process data (docs/fastcat-coupler.md "Module alarms keep OP")."""
    runtime, _bridge, b = wire
    fastcat = runtime.rig.devices["fastcat"]

    def fault_bit() -> int:
        b.send(msg.CYCLE, {0: 3})  # frames: the bridge sends the SM3 image when it changed
        return sim(runtime, lambda: faces.inputs(fastcat)[0] & 1)

    b.expect(lambda m: m == (msg.AL_STATUS, 0, 8, 0))
    runtime.command("fastcat/3", "inject_fault", {"fault": "TARATURA"}).result(timeout=WAIT_S)
    reply = b.expect(lambda m: m[:2] == (msg.MAILBOX_REPLY, 0) and m[2][6:8] == b"\x00\x10")
    assert reply[2][8:].hex(" ") == "00 ff 81 03 00 0b 00 00"
    wait_for(lambda: fault_bit() == 1)
    b.expect(lambda m: m[:2] == (msg.INPUTS, 0) and m[2][0] & 1)
    runtime.command("fastcat/3", "clear_fault", {"fault": "TARATURA"}).result(timeout=WAIT_S)
    b.send(msg.OUTPUTS, 0, (1).to_bytes(3, "little"))  # the Reset fault bit rises, in OP
    wait_for(lambda: fault_bit() == 0)
    b.expect(lambda m: m[:2] == (msg.INPUTS, 0) and not m[2][0] & 1)
    assert sim(runtime, lambda: (fastcat.alarm, fastcat.al_status, fastcat.al_status_code)) \
        == (None, 8, 0)
    assert not [m for m in b.seen if m[0] == msg.AL_STATUS and m[1] == 0]  # never left OP
