"""Alarms as CoE emergencies with the 0x603F codes, and the alarm reset with 0x80 on 0x6040
(seed 004 ch. 5 "Codici allarmi specifici", "Reset allarmi"; emergency layout of ch. 4).
"""

from __future__ import annotations

import random

import pytest
from coe_bench import CIA402_ENABLE, Bench, make_bench

from devices.ethercat import AlState
from devices.master import EtherCatMaster

P = AlState.PREOP

# Ch. 5 table "Codice Allarme ECO / Error Code 0x603F sub0", as printed (30 has none).
ERROR_CODES = {
    1: 0x2340, 2: 0x7120, 3: 0x2310, 4: 0x3210, 5: 0x3220, 6: 0x4310, 7: 0x5220, 8: 0x7300,
    9: 0x5500, 10: 0x7110, 11: 0x7500, 12: 0x7320, 13: 0x7500, 14: 0x7320, 15: 0x5500,
    16: 0x8611, 20: 0x8612, 21: 0x8612, 23: 0x7300, 24: 0x7300, 25: 0x7300, 26: 0x5114,
    31: 0x7500, 32: 0x7500, 33: 0x6320, 34: 0x8700, 35: 0x5530,
}
# DS 301 error register bits of the code class (ch. 4): generic always, + current 2xxx,
# voltage 3xxx, temperature 4xxx, device profile 86xx / 87xx.
REGISTER = {0x2: 0x03, 0x3: 0x05, 0x4: 0x09, 0x8: 0x21}


# 35 (EtherCAT EEPROM) takes the slave to INIT, whose mailbox stops: its 0x5530 stays in
# 0x1003 (test_coe_booting_error.py).
@pytest.mark.parametrize(("alarm", "code"), [(a, c) for a, c in ERROR_CODES.items() if a != 35])
def test_alarm_sent_as_emergency_with_its_0x603f_code(alarm: int, code: int) -> None:
    bench = make_bench()
    bench.go(P)
    bench.drive.apply("inject_alarm", {"code": str(alarm)})
    bench.run(1)
    register = REGISTER.get(code >> 12, 0x01)
    assert bench.emergencies == [code.to_bytes(2, "little") + bytes((register, alarm, 0, 0, 0, 0))]
    assert bench.read(0x603F) == code
    assert bench.read(0x1001) == register
    assert bench.read(0x1003, 1) == alarm << 16 | code
    record = bench.kinds("emergency")[-1]
    assert (record["device"], record["code"]) == ("servo", f"0x{code:04X}")


def test_emergencies_wait_for_the_mailbox() -> None:
    """An alarm raised in INIT (no mailbox) is sent once the slave is in PREOP."""
    bench = make_bench()
    bench.drive.apply("inject_alarm", {"code": "5"})
    bench.run(5)
    assert bench.emergencies == [] and bench.slave.take_emergencies() == []
    bench.go(P)
    bench.run(1)
    assert [frame[:2] for frame in bench.emergencies] == [b"\x20\x32"]


def unread_emergency(bench: Bench) -> None:
    """Alarm 5 (0x3220) raised in PREOP with the cable out: queued, the master cannot read it."""
    bench.go(P)
    bench.slave.set_link(False)
    bench.drive.apply("inject_alarm", {"code": "5"})
    bench.run(5)
    assert [r["code"] for r in bench.kinds("emergency")] == ["0x3220"]
    assert bench.emergencies == []
    bench.slave.set_link(True)


def test_unread_emergencies_are_lost_through_init() -> None:
    """The mailbox stops on the way to INIT and its queue goes (ETG.1000.6, SSC
    MBX_StopMailboxHandler); 0x1003 is an object and keeps the alarm."""
    bench = make_bench()
    unread_emergency(bench)
    bench.go(AlState.INIT, P)
    bench.run(5)
    assert bench.emergencies == []
    assert bench.read(0x1003, 1) == 5 << 16 | 0x3220


def test_unread_emergencies_wait_without_init() -> None:
    bench = make_bench()
    unread_emergency(bench)
    bench.run(1)
    assert [frame[:2] for frame in bench.emergencies] == [b"\x20\x32"]


def test_reset_with_0x80_on_0x6040() -> None:
    """Ch. 5 "Reset allarmi": "scrittura 0x80 su oggetto 0x6040. Nel caso in cui
    l'operazione non abbia successo, può significare che la condizione di allarme persiste"."""
    bench = make_bench()
    bench.go(P)
    bench.cw(*CIA402_ENABLE)
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(5)
    assert bench.drive.state.label == "Fault"
    bench.cw(0x0080, 0x0000)
    assert bench.drive.state.label == "Fault"  # the cause is still there
    assert bench.read(0x603F) == 0x8611
    bench.drive.apply("clear_alarm", {"code": "16"})
    bench.cw(0x0080, 0x0000)
    bench.run(1)
    assert bench.drive.state.label == "Switch on disabled"
    assert bench.read(0x603F) == 0
    assert bench.emergencies[-1] == bytes(8)  # DS 301 "error reset"
    assert bench.read(0x1001) == 0
    bench.cw(0x0006, 0x0007, 0x000F)
    assert bench.drive.state.label == "Operation enabled"


def test_history_sub0_takes_only_zero() -> None:
    bench = make_bench()
    bench.go(P)
    bench.drive.apply("inject_alarm", {"code": "4"})
    bench.run(1)
    assert bench.read(0x1003, 0) == 1
    bench.write(0x1003, 0, 0, 1)
    assert (bench.read(0x1003, 0), bench.read(0x1003, 1)) == (0, 0)


def test_the_master_logs_the_emergency_frames() -> None:
    bench = make_bench()
    master = EtherCatMaster("master", random.Random(1), slaves=[bench.slave])
    bench.cycling = bench.reads_mailbox = False
    for _ in range(1000):
        bench.step()
        master.step(bench.t_us)
    bench.drive.apply("inject_alarm", {"code": "34"})
    bench.step()
    master.step(bench.t_us)
    assert any("CoE - Emergency" in line["text"] for line in master.log)
    assert bench.slave.take_emergencies() == []  # the master took them from the mailbox
