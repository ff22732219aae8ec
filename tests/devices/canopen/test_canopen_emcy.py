"""Emergency messages from drive alarms (seed 004 ch. 4 "Emergency Message": code, error
register [1001], vendor field; history [1003]; COB-ID [1014]; ch. 5 table of 0x603F codes).
"""

from __future__ import annotations

import pytest
from canopen_bench import hexs, make_bench

from devices.canopen import emcy as em
from devices.canopen.nmt import NmtCommand
from devices.servo.alarms import alarm_table

ALARMS = sorted(alarm_table("canopen").values(), key=lambda a: a.code)


def _emcys(bench) -> list:
    return [f for f in bench.take() if f.can_id == 0x081]


@pytest.mark.parametrize("alarm", ALARMS, ids=lambda a: f"{a.code}-{a.name}")
def test_injected_alarm_arrives_as_emcy_with_its_603F_code(alarm) -> None:
    bench = make_bench()
    bench.take()
    bench.drive.apply("inject_alarm", {"code": str(alarm.code)})
    bench.run(5)
    code = alarm.error_code_or_generic
    register = em.register_bits(code)
    frames = _emcys(bench)
    expected = em.payload(code, register, bytes((alarm.code,)))
    assert [hexs(f.data) for f in frames] == [hexs(expected)]
    assert bench.read(0x1001) == register
    assert bench.read(0x1003, 1) == alarm.code << 16 | code
    event = bench.kinds("emergency")[-1]
    assert event["code"] == f"0x{code:04X}" and event["device"] == "servo"


@pytest.mark.parametrize(("code", "bits"), [
    (0x2310, 0x03), (0x3210, 0x05), (0x4310, 0x09), (0x8130, 0x11), (0x8611, 0x21),
    (0x5500, 0x01), (0x7300, 0x01), (0x1000, 0x01), (0xFF01, 0x81), (0x0000, 0x00),
])
def test_error_register_bits_by_code_class(code: int, bits: int) -> None:
    """Bit 0 generic with every error; 1 current (2xxx), 2 voltage (3xxx), 3 temperature
    (4xxx), 4 communication (81xx, 82xx), 5 device profile (86xx, 87xx), 7 manufacturer."""
    assert em.register_bits(code) == bits


def test_reset_sends_error_reset_and_clears_the_register() -> None:
    """Alarm 16, cause removed, reset with 0x6040 bit 7 (0x0080): EMCY 0x0000, 0x1001 = 0."""
    bench = make_bench()
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(5)
    bench.drive.apply("clear_alarm", {"code": "16"})
    bench.take()
    bench.ok(0x6040, 0, 0x0000, 2)
    bench.ok(0x6040, 0, 0x0080, 2)
    bench.run(5)
    assert [hexs(f.data) for f in _emcys(bench)] == ["00 00 00 00 00 00 00 00"]
    assert bench.read(0x1001) == 0
    assert bench.read(0x1003, 1) == 0x0010_8611  # the history keeps it


def test_inhibit_time_spaces_emergencies() -> None:
    """0x1015 in 100 us: two alarms at once leave 50 ms apart."""
    bench = make_bench()
    bench.ok(0x1015, 0, 500, 2)
    bench.take()
    bench.drive.apply("inject_alarm", {"code": "2"})
    bench.drive.apply("inject_alarm", {"code": "6"})
    bench.run(100)
    times = [f.t_us for f in _emcys(bench)]
    assert len(times) == 2 and times[1] - times[0] >= 50_000


@pytest.mark.parametrize(("setup", "sent"), [
    ("invalid", False),  # 0x1014 bit 31: no emergency object
    ("stopped", False),  # Stopped: only NMT and guarding
    ("operational", True),
])
def test_when_emergencies_leave(setup: str, sent: bool) -> None:
    bench = make_bench()
    if setup == "invalid":
        bench.ok(0x1014, 0, 0x8000_0081, 4)
    elif setup == "stopped":
        bench.nmt(NmtCommand.STOP)
    else:
        bench.nmt(NmtCommand.START)
    bench.take()
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(5)
    assert bool(_emcys(bench)) is sent
    assert bench.node.history.latest == 0x0010_8611  # recorded either way


def test_alarm_at_power_up_is_sent_after_boot_up() -> None:
    """A flash that does not load raises alarm 9 at power-up: its EMCY follows the boot-up."""
    bench = make_bench(boot=False)
    bench.flash.save(b"not a drive image")
    bench.drive.apply("power", {"on": False})
    bench.drive.apply("power", {"on": True})
    bench.run(60)
    frames = [(f.can_id, hexs(f.data)) for f in bench.take()]
    assert frames[-2:] == [(0x701, "00"), (0x081, "00 55 01 09 00 00 00 00")]


def test_the_bus_monitor_names_the_alarm_of_its_own_emcy() -> None:
    """The CANopen tab's frame log: the vendor byte is hex ("10" for alarm 16), the drive
    numbers its alarms in decimal (ch. 3), so the meaning names the alarm. Another node's
    EMCY on the bus is not this drive's to read."""
    bench = make_bench()
    bench.take()
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(5)
    bench.send(0x083, em.payload(0x8611, 0x21, bytes((16,))))  # node 3's, same bytes
    bench.run(5)
    texts = [f["text"] for f in bench.node.snapshot()["frames"] if f["kind"] == "EMCY"]
    assert texts == ["node 1: code 0x8611, register 0x21, data 10 00 00 00 00: "
                     "alarm 16 FOLLOWING_ERROR",
                     "node 3: code 0x8611, register 0x21, data 10 00 00 00 00"]


@pytest.mark.parametrize(("command", "state"), [
    (NmtCommand.START, "Operational"), (NmtCommand.ENTER_PRE_OPERATIONAL, "Pre-operational"),
])
def test_an_emergency_raised_while_stopped_leaves_when_the_node_may_speak(command, state) -> None:
    """Stopped sends no EMCY ("non può trasmettere ... qualsiasi altro messaggio che il node
    guarding o l'heartbeat"), but the error event stays owed: the EMCY leaves as soon as the
    node is in Pre-operational or Operational again (docs/canopen.md §Emergencies)."""
    bench = make_bench()
    bench.nmt(NmtCommand.STOP)
    bench.take()
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(500)
    assert _emcys(bench) == []
    bench.send(0x000, bytes((command, 1)))
    bench.run(5)
    changed = [e for e in bench.kinds("state") if e["to"] == state][-1]
    frames = _emcys(bench)
    assert [hexs(f.data) for f in frames] == ["11 86 21 10 00 00 00 00"]
    assert 0 <= frames[0].t_us - round(changed["t"] * 1e6) <= 2_000
    assert bench.kinds("emergency")[-1]["code"] == "0x8611"
    bench.run(500)
    assert _emcys(bench) == []  # once per error event


def test_emergencies_of_an_error_come_and_gone_while_stopped_leave_in_order() -> None:
    """Alarm 2 raised and reset while Stopped (the reset pulse from the drive's own side):
    after Start the master hears both, the error and the error reset, spaced by 0x1015."""
    bench = make_bench()
    bench.ok(0x1015, 0, 100, 2)  # 10 ms
    bench.nmt(NmtCommand.STOP)
    bench.take()
    bench.drive.apply("inject_alarm", {"code": "2"})
    bench.run(20)
    bench.drive.apply("clear_alarm", {"code": "2"})
    bench.drive.apply("alarm_reset", {})
    bench.run(20)
    assert _emcys(bench) == []
    assert bench.drive.alarms.latched == []
    bench.nmt(NmtCommand.START)
    bench.run(30)
    frames = _emcys(bench)
    assert [hexs(f.data)[:5] for f in frames] == ["20 71", "00 00"]
    assert frames[1].t_us - frames[0].t_us >= 10_000


def test_an_emergency_waiting_for_its_inhibit_time_at_stop_is_kept() -> None:
    """Two alarms at once with 0x1015 = 50 ms, Stop between them: the second, not yet sent,
    leaves after Start instead of being lost."""
    bench = make_bench()
    bench.ok(0x1015, 0, 500, 2)
    bench.take()
    bench.drive.apply("inject_alarm", {"code": "2"})
    bench.drive.apply("inject_alarm", {"code": "6"})
    bench.run(10)
    assert len(_emcys(bench)) == 1
    bench.nmt(NmtCommand.STOP)
    bench.run(200)
    assert _emcys(bench) == []
    bench.nmt(NmtCommand.START)
    bench.run(5)
    assert len(_emcys(bench)) == 1


def test_a_life_guard_error_of_the_stopped_node_leaves_after_start() -> None:
    """Life guarding runs in Stopped (guarding is what Stopped keeps): its EMCY 0x8130 waits
    for the Start like a drive alarm's."""
    bench = make_bench()
    bench.ok(0x100C, 0, 100, 2)
    bench.ok(0x100D, 0, 2, 1)
    bench.nmt(NmtCommand.STOP)
    bench.send(0x701, rtr=True, dlc=1)
    bench.run(500)
    assert bench.node.life_guard_error and _emcys(bench) == []
    bench.nmt(NmtCommand.START)
    assert [hexs(f.data) for f in _emcys(bench)] == ["30 81 11 00 00 00 00 00"]


def test_an_alarm_still_latched_at_reset_communication_is_sent_after_the_boot_up() -> None:
    """Reset-Communication brings the communication profile back to its power-on values (ch.
    4 "Stati e Cambiamento di stato"): the node starts over as at power-up, and an alarm that
    is still latched is an active error it reports again, boot-up first, then its EMCY, once;
    0x1003 (cleared by the reset) records it again, 0x1001 keeps its bits throughout
    (docs/canopen.md §Emergencies)."""
    bench = make_bench()
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(5)
    bench.take()
    bench.nmt(NmtCommand.RESET_COMMUNICATION)
    bench.run(50)
    frames = [(f.can_id, hexs(f.data)) for f in bench.take()]
    assert frames == [(0x701, "00"), (0x081, "11 86 21 10 00 00 00 00")]
    assert [e["code"] for e in bench.kinds("emergency")] == ["0x8611", "0x8611"]
    assert bench.read(0x1001) == 0x21
    assert (bench.read(0x1003, 0), bench.read(0x1003, 1)) == (1, 0x0010_8611)
    bench.run(500)
    assert _emcys(bench) == []  # once per error event


def test_an_alarm_held_in_stopped_is_not_lost_by_a_reset_communication() -> None:
    """The EMCY held in Stopped goes with the rest of the communication state at the reset,
    but the alarm it told of is still latched: it is sent after the boot-up."""
    bench = make_bench()
    bench.nmt(NmtCommand.STOP)
    bench.drive.apply("inject_alarm", {"code": "2"})
    bench.run(20)
    assert _emcys(bench) == []
    bench.nmt(NmtCommand.RESET_COMMUNICATION)
    bench.run(50)
    assert [hexs(f.data)[:5] for f in _emcys(bench)] == ["20 71"]
