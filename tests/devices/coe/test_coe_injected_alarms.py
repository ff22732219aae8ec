"""An instructor's injected alarm 33 / 34 on an EtherCAT drive shows what a master sees for the
real fault (seed 004 ch. 5 "Codici allarmi specifici" l. 4866-4867, "Stati macchina",
"Transizioni", "Reset allarmi"; docs/ethercat-coe.md "Drive alarms and the EtherCAT side").

Until session 21 an injected 33 or 34 only latched the alarm: the slave stayed in OP with ERR
dark, while the injected 7 / 30-32 / 35 drove the ESM; and a valid mapping passing
PREOP -> SAFEOP took the injected 33's cause away, so a trainee could reset it.
"""

from __future__ import annotations

from coe_bench import Bench, make_bench, with_master

from devices.ethercat import AlState

PREOP, SAFEOP, OP = AlState.PREOP, AlState.SAFEOP, AlState.OP
SM_WATCHDOG = 0x001B
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


# ---- 34: the sync timeout -----------------------------------------------------------------
def test_an_injected_34_in_op_is_the_sm_watchdog_fall() -> None:
    """As test_coe_esm's watchdog: SAFEOP + error with 0x001B, ERR double flash, 0x8700."""
    bench = make_bench()
    bench.up_to(OP)
    inject(bench, 34)
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (SAFEOP, 0x14, SM_WATCHDOG)
    assert slave.leds.snapshot()["Error"] == "double_flash"
    assert [frame[:2] for frame in bench.emergencies] == [b"\x00\x87"]  # 0x8700
    assert bench.read(0x603F) == 0x8700
    assert bench.kinds("state")[-1]["to"] == "SAFEOP"
    assert bench.kinds("al_status")[-1]["code"] == "0x001B"
    assert logged(bench, "alarm 34", "0x001B", "OP -> SAFEOP")
    assert not logged(bench, "inject")


def test_op_refused_with_0x001b_while_the_injected_34_stands_then_the_real_recovery() -> None:
    bench = make_bench()
    bench.up_to(OP)
    inject(bench, 34)
    slave = bench.slave
    bench.go(OP)
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (SAFEOP, 0x14, SM_WATCHDOG)
    assert slave.leds.snapshot()["Error"] == "double_flash"
    reset_over_coe(bench)
    assert bench.drive.alarms.latched == [34]  # the cause stands
    bench.drive.apply("clear_alarm", {"code": "34"})
    reset_over_coe(bench)
    assert bench.drive.alarms.latched == []
    bench.go(OP)
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (OP, 0x08, 0)
    assert slave.leds.snapshot()["Error"] == "off"


def test_an_injected_34_below_op_lets_the_slave_up_to_safeop_only() -> None:
    bench = make_bench()
    bench.up_to(PREOP)
    inject(bench, 34)
    assert bench.slave.al_status_code == 0  # nothing to fall from: no process data yet
    bench.go(SAFEOP, OP)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (SAFEOP, SM_WATCHDOG)


def test_the_built_in_master_keeps_an_injected_34_in_safeop_until_cleared() -> None:
    bench = make_bench()
    _, run = with_master(bench)

    run(1000)
    assert bench.slave.al_state is OP
    bench.drive.apply("inject_alarm", {"code": "34"})
    run(1000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (SAFEOP, SM_WATCHDOG)
    bench.drive.apply("clear_alarm", {"code": "34"})
    run(1000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (OP, 0)
    bench.write(0x6040, 0, 0x0080, 2)
    bench.write(0x6040, 0, 0x0000, 2)
    assert bench.drive.alarms.latched == []



def test_a_quiet_span_ends_at_an_injected_34_in_op() -> None:
    """quiet_until must not let a span skip the step that takes the slave out of OP, even
    with the emergency watch up to date (its own reason to end a span)."""
    bench = make_bench()
    bench.up_to(OP)
    bench.drive.apply("inject_alarm", {"code": "34"})
    bench.slave.emergencies.known = list(bench.drive.alarms.latched)
    assert bench.slave.quiet_until(1_000) == bench.slave.now_us
