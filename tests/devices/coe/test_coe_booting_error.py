"""Alarm 35 "Errore caricamento eeprom ethercat" (seed 004 ch. 5 "Codici allarmi specifici",
0x5530) and the Error LED (ch. 5 "Connessioni e Leds Drive EtherCAT": "La frequenza di
lampeggio è funzione della tipologia di allarme ... ETG-1300").

ETG.1300's ERR row for an EEPROM that did not load is flickering, "booting error: INIT state
reached, but the error indicator bit is set in the AL status register". The drive flickered
ERR while it stayed in OP with Status on: a pair of patterns ETG.1300 does not have, which a
trainee cannot read. The slave now falls to INIT + error with ETG.1000.6's 0x0051 "EEPROM
Error" and stays there while the alarm is latched (docs/ethercat-coe.md §LEDs).
"""

from __future__ import annotations

import pytest
from coe_bench import Bench, make_bench, with_master

from devices.ethercat import AlState

INIT, PREOP, SAFEOP, OP = AlState.INIT, AlState.PREOP, AlState.SAFEOP, AlState.OP
EEPROM_ERROR = 0x0051


def power_cycle(bench: Bench) -> None:
    """The drive switched off and on: the ESC loads its EEPROM again at start-up."""
    bench.drive.apply("power", {"on": False})
    bench.run(100)
    bench.drive.apply("power", {"on": True})
    bench.run(100)


@pytest.mark.parametrize("start", [PREOP, SAFEOP, OP], ids=lambda s: s.label)
def test_alarm_35_is_a_booting_error_in_init(start: AlState) -> None:
    bench = make_bench()
    bench.up_to(start)
    bench.drive.apply("inject_alarm", {"code": "35"})
    bench.run(1)
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (INIT, 0x11, EEPROM_ERROR)
    assert slave.leds.snapshot() == {"L/A IN": "flickering", "Status": "off", "L/A OUT": "off",
                                     "Error": "flickering"}
    assert bench.kinds("al_status")[-1]["code"] == "0x0051"


def test_err_flickers_only_in_init() -> None:
    """Step by step from OP through the alarm, its reset and the way back: never a flickering
    ERR next to a lit Status (ETG.1300 flickering = booting error = INIT)."""
    bench = make_bench()
    bench.up_to(OP)
    seen = set()

    def watch(ms: int) -> None:
        for _ in range(ms):
            bench.step()
            leds = bench.slave.leds.snapshot()
            seen.add((bench.slave.al_state, leds["Error"], leds["Status"]))

    bench.drive.apply("inject_alarm", {"code": "35"})
    watch(50)
    bench.go(PREOP)
    watch(50)
    assert {(s, e) for s, e, _ in seen if e == "flickering"} == {(INIT, "flickering")}
    assert all(status == "off" for _, e, status in seen if e == "flickering")


def test_init_to_preop_is_refused_while_alarm_35_is_latched() -> None:
    bench = make_bench()
    bench.up_to(OP)
    bench.drive.apply("inject_alarm", {"code": "35"})
    bench.run(1)
    bench.go(PREOP)
    slave = bench.slave
    assert (slave.al_state, slave.al_status_code) == (INIT, EEPROM_ERROR)
    assert slave.leds.snapshot()["Error"] == "flickering"  # still the booting error
    bench.drive.apply("clear_alarm", {"code": "35"})
    # INIT has no mailbox and no process data: no 0x6040 write reaches the drive, and the
    # dashboard's Alarm reset (that write) is refused as such
    assert bench.drive.apply("alarm_reset", {}) == (
        "alarm 35 is not resettable: switch the drive off and on")
    bench.run(1)
    assert bench.drive.alarms.latched == [35]
    bench.go(PREOP)
    assert (slave.al_state, slave.al_status_code) == (INIT, EEPROM_ERROR)
    power_cycle(bench)
    assert bench.drive.alarms.latched == []
    bench.go(PREOP)
    assert (slave.al_state, slave.al_status_code) == (PREOP, 0)
    assert slave.leds.snapshot()["Error"] == "off"
    assert bench.read(0x1003, 1) == 0  # the power cycle emptied the history with the rest


def test_the_built_in_master_reads_the_eeprom_error_and_retries() -> None:
    bench = make_bench()
    master, run = with_master(bench)

    run(1000)
    assert bench.slave.al_state is OP
    bench.drive.apply("inject_alarm", {"code": "35"})
    run(1000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (INIT, EEPROM_ERROR)
    texts = [row["text"] for row in master.log]
    assert any("abnormal state change (from 'OP' to 'INIT') with code 0x0051" in t
               for t in texts)
    assert any("'INIT to PREOP' failed!" in t and "'0x0051'" in t for t in texts)
    bench.drive.apply("clear_alarm", {"code": "35"})
    bench.drive.apply("alarm_reset", {})  # refused: the slave stays in INIT
    run(1000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (INIT, EEPROM_ERROR)
    bench.drive.apply("power", {"on": False})
    run(100)
    bench.drive.apply("power", {"on": True})
    run(3000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (OP, 0)
    assert bench.slave.leds.snapshot()["Error"] == "off"
