"""An instructor's injected alarm 33 / 34 on an EtherCAT drive shows what a master sees for the
real fault (seed 004 ch. 5 "Codici allarmi specifici" l. 4866-4867, "Stati macchina",
"Transizioni", "Reset allarmi"; docs/ethercat-coe.md "Drive alarms and the EtherCAT side").

Until session 21 an injected 33 or 34 only latched the alarm: the slave stayed in OP with ERR
dark, while the injected 7 / 30-32 / 35 drove the ESM; and a valid mapping passing
PREOP -> SAFEOP took the injected 33's cause away, so a trainee could reset it.
"""

from __future__ import annotations

from coe_bench import Bench, make_bench

from devices.ethercat import AlState

PREOP, SAFEOP, OP = AlState.PREOP, AlState.SAFEOP, AlState.OP
INVALID_OUTPUT_MAPPING = 0x0025


def inject(bench: Bench, code: int) -> None:
    bench.drive.apply("inject_alarm", {"code": str(code)})
    bench.run(1)


def reset_over_coe(bench: Bench) -> None:
    bench.cw(0x0080, 0x0000)  # ch. 5 "Reset allarmi": 0x80 on 0x6040, by SDO


def logged(bench: Bench, *words: str) -> bool:
    return any(all(w in e["text"] for w in words) for e in bench.kinds("log"))


# ---- 33: the PDO mapping ----------------------------------------------------------------
def test_an_injected_33_stands_after_a_valid_mapping_passes_until_the_instructor_clears_it(
        ) -> None:
    bench = make_bench()
    bench.up_to(OP)
    inject(bench, 33)
    bench.go(PREOP, SAFEOP)  # the default mapping is valid
    reset_over_coe(bench)
    assert bench.drive.alarms.latched == [33]  # "la condizione di allarme persiste"
    assert [i["code"] for i in bench.drive.snapshot()["injected"]] == [33]
    bench.drive.apply("clear_alarm", {"code": "33"})
    bench.go(PREOP, SAFEOP)
    reset_over_coe(bench)
    assert bench.drive.alarms.latched == []
    assert bench.drive.snapshot()["injected"] == []

def test_an_injected_33_leaves_op_alone() -> None:
    """The mapping is checked at PREOP -> SAFEOP: in OP the process data go on."""
    bench = make_bench()
    bench.up_to(OP)
    inject(bench, 33)
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (OP, 0x08, 0)
    assert slave.leds.snapshot()["Error"] == "off"
    assert [frame[:2] for frame in bench.emergencies] == [b"\x20\x63"]  # 0x6320


def test_an_injected_33_refuses_safeop_with_0x0025_until_cleared() -> None:
    bench = make_bench()
    bench.up_to(PREOP)
    inject(bench, 33)
    bench.go(SAFEOP)
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (
        PREOP, 0x12, INVALID_OUTPUT_MAPPING)
    assert slave.leds.snapshot()["Error"] == "blinking"  # ETG.1300 invalid configuration
    assert bench.read(0x603F) == 0x6320
    assert logged(bench, "PREOP -> SAFEOP", "alarm 33")
    assert not logged(bench, "inject")  # the drive log reaches a trainee's page
    bench.drive.apply("clear_alarm", {"code": "33"})
    bench.go(SAFEOP)
    assert (slave.al_state, slave.al_status_code) == (SAFEOP, 0)
    reset_over_coe(bench)
    assert bench.drive.alarms.latched == []
    bench.go(OP)
    assert (slave.al_state, slave.al_status_code) == (OP, 0)
    assert slave.leds.snapshot()["Error"] == "off"

