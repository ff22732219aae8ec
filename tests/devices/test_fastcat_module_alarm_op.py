"""A module alarm (seed 000 §7.6) keeps the coupler's ESM where it is; a coupler alarm (§7.5)
still takes it to PREOP with 0x80XX (§7.7).

§7: the resettable emergencies are reset by raising Reset fault, "mappato nei dati scambiati
con il coupler" (0x16FF, §5, §6.17), and Fault active travels in 0x1AFF (§6.16): both need
process data, so a module alarm cannot stop it. §7.7: the manufacturer AL status code carries
"allarmi gravi generati dal coupler", and only coupler codes are ever shown there
(docs/fastcat-coupler.md "Module alarms keep OP").
"""

from __future__ import annotations

from fastcat_bench import Bench

from devices.ethercat import AlState

FAULT_ACTIVE = (0x5100, 1)  # §6.16, mapped in 0x1AFF
RESET_FAULT = (0x5200, 1)  # §6.17, mapped in 0x16FF


def _op_with_output() -> Bench:
    """DO16 (output 1 on) and AI8D in OP: the AI8D's alarms are module alarms of module 2."""
    bench = Bench(["DO16", "AI8D"])
    bench.to_state(AlState.OP)
    bench.write(0x7000, 1, 1)
    bench.step()
    assert bench.fc.snapshot()["rail"][0]["do"][0] is True
    return bench


def test_module_alarm_in_op_keeps_op_without_al_status_code() -> None:
    bench = _op_with_output()
    since = bench.mark()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(0.5)
    assert bench.emergencies(since) == ["02 00 0B 00 00"]  # §7.2 Sirio example, byte 2
    assert bench.fc.al_state is AlState.OP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x08, 0)  # no error flag
    assert bench.records("al_status", since) == []
    assert bench.records("state", since) == []
    assert bench.read(0x5400, 0) == 0x000B0002
    assert bench.read(*FAULT_ACTIVE) is True
    assert bench.read(0x1AFF, 1) == 0x5100_0101  # Fault active is in the cyclic TxPDO
    # §7 last paragraph: every module in alarm, outputs in the safe state
    assert all(m.in_alarm for m in bench.fc.modules())
    assert bench.fc.snapshot()["rail"][0]["do"][0] is False
    assert bench.read(0x7000, 1) == 1  # the master's image is kept


def test_reset_fault_through_process_data_in_op_clears_a_module_alarm() -> None:
    bench = _op_with_output()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(0.1)
    bench.apply("clear_fault", module=2, fault="TARATURA")
    bench.run(0.1)
    assert bench.fc.alarm is not None  # latched until the reset
    since = bench.mark()
    bench.write(*RESET_FAULT, 1)  # the 0x16FF bit's rising edge, the line still in OP
    bench.step()
    assert bench.fc.alarm is None and bench.read(*FAULT_ACTIVE) is False
    assert bench.read(0x5400, 0) == 0
    assert [(r["code"], r["active"]) for r in bench.records("alarm", since)] == \
        [("0x0B", False)]
    assert bench.fc.al_state is AlState.OP and bench.records("state", since) == []
    assert not any(m.in_alarm for m in bench.fc.modules())
    assert bench.fc.snapshot()["rail"][0]["do"][0] is True


def test_a_module_alarm_refuses_no_state_request() -> None:
    """Latched in PREOP, it does not bar PREOP -> SAFEOP -> OP."""
    bench = Bench(["DO16", "AI8D"])
    bench.to_state(AlState.PREOP)
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.step()
    assert bench.fc.alarm is not None
    bench.start_frames()  # the master's process data (the SM watchdog wants them for OP)
    for target in (AlState.SAFEOP, AlState.OP):
        bench.fc.request_state(target)
        assert bench.fc.al_state is target
        assert (bench.fc.al_status, bench.fc.al_status_code) == (int(target), 0)
    bench.step()
    assert bench.fc.snapshot()["rail"][0]["do"][0] is False  # still in alarm: safe state


def test_module_alarm_leds_module_reds_on_err_follows_the_error_flag() -> None:
    """§2 / §7: every module's red on, yellow off; ERR (ETG.1300) follows the AL status error
    flag, which a module alarm does not set: off while RUN stays on."""
    bench = _op_with_output()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(0.1)
    leds = bench.fc.snapshot()["leds"]
    assert (leds["1.red"], leds["1.yellow"], leds["2.red"], leds["2.yellow"]) == \
        ("on", "off", "on", "off")
    assert (leds["RUN"], leds["ERR"]) == ("on", "off")


def test_a_coupler_alarm_still_drops_op_to_preop() -> None:
    bench = _op_with_output()
    since = bench.mark()
    bench.apply("inject_fault", module=2, fault="MISSING_NODE_ANSWER")
    bench.step()
    assert bench.emergencies(since) == ["02 00 00 04 00"]
    assert bench.fc.al_state is AlState.PREOP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x12, 0x8204)
    assert bench.fc.snapshot()["leds"]["ERR"] == "single_flash"
    bench.fc.request_state(AlState.SAFEOP)
    assert bench.fc.al_state is AlState.PREOP and bench.fc.al_status_code == 0x8204


def test_the_master_keeps_the_line_in_op_and_logs_only_the_emergency() -> None:
    """The built-in master reads the §7.1 emergency; no abnormal state change to log."""
    bench = Bench(["DO16", "AI8D"], master=True)
    bench.run_until(lambda: bench.fc.al_state is AlState.OP)
    bench.run(0.5)
    since = bench.mark()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(3.0)
    texts = [r["text"] for r in bench.records("log", since)]
    assert texts == ["'Box 1 (FastCAT)' (1001): CoE - Emergency (Hex: ff00, 81, "
                     "02 00 0b 00 00')."]  # lower case, as TwinCAT
    assert bench.records("slave_state", since) == []
    assert bench.fc.al_state is AlState.OP


def test_a_coupler_cause_behind_a_module_alarm_waits_and_everything_says_so() -> None:
    """§7: "Il coupler segnalerà il primo allarme ricevuto ... Non si potranno mai verificare
    contemporaneamente errori segnalati dal coupler e dai moduli". A module pulled while a
    module alarm is latched (the §7.7 example's cause) is not signalled: ESM, AL status code,
    LEDs, 0x5400 and the emergencies all keep telling the first alarm, and the master logs
    nothing new. Once the module alarm is reset, the coupler alarm is the next one: its
    emergency, 0x8304 and the drop to PREOP come at once (docs/fastcat-coupler.md
    "A coupler cause behind a module alarm")."""
    bench = Bench(["DO16", "AI8D", "DI16"], master=True)
    bench.run_until(lambda: bench.fc.al_state is AlState.OP)
    bench.run(0.5)
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(1.0)
    since = bench.mark()
    bench.apply("unplug", module=3)
    bench.run(3.0)
    assert bench.emergencies(since) == [] and bench.records("alarm", since) == []
    assert bench.records("al_status", since) == [] and bench.records("state", since) == []
    assert [r["text"] for r in bench.records("log", since)] == []
    assert bench.fc.al_state is AlState.OP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x08, 0)
    assert bench.read(0x5400, 0) == 0x000B0002 and bench.read(*FAULT_ACTIVE) is True
    leds = bench.fc.snapshot()["leds"]
    assert (leds["RUN"], leds["ERR"]) == ("on", "off")
    assert [leds[f"{n}.red"] for n in (1, 2)] == ["on", "on"] and "3.red" not in leds
    bench.apply("clear_fault", module=2, fault="TARATURA")
    since = bench.mark()
    bench.reset_fault()
    bench.run(0.5)
    assert [(r["code"], r["active"], r["module"]) for r in bench.records("alarm", since)] == \
        [("0x0B", False, 2), ("0x04", True, 3)]
    assert bench.emergencies(since) == ["03 00 00 04 00"]  # §7.4's data, as byte 3 = 0x04
    assert [r["code"] for r in bench.records("al_status", since)] == ["0x8304"]
    assert bench.fc.al_state is AlState.PREOP and bench.read(0x5400, 0) == 0x04000003
    assert [r["to"] for r in bench.records("slave_state", since)] == ["PREOP"]


def test_an_address_check_behind_a_module_alarm_waits_and_op_is_reached() -> None:
    """§6.19: the address check runs "quando il modulo viene portato nello stato di
    operativo". With a module alarm latched, its 0x12 is a coupler cause behind it, which
    waits like the others (docs "A coupler cause behind a module alarm": no emergency, the
    module alarm's 0x5400, no transition refused). The OP request used to be left unanswered:
    SAFEOP, no error flag, no code, OP requested. Once the module alarm is reset, 0x12 is
    latched with its emergency (0x5400 = 0x12000000) and the drop to PREOP with 0x8012."""
    bench = Bench(["DO16", "AI8D"], rotary_switch=3, master_address=2)
    bench.to_state(AlState.PREOP)
    bench.write(0x5301, 0, 1)
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.step()
    bench.start_frames()  # the master's process data (the SM watchdog wants them for OP)
    bench.fc.request_state(AlState.SAFEOP)
    since = bench.mark()
    bench.fc.request_state(AlState.OP)
    bench.run(0.1)
    assert bench.fc.al_state is AlState.OP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x08, 0)
    assert bench.emergencies(since) == [] and bench.read(0x5400, 0) == 0x000B0002
    bench.apply("clear_fault", module=2, fault="TARATURA")
    since = bench.mark()
    bench.reset_fault()
    bench.step()
    assert bench.emergencies(since) == ["00 00 00 12 00"]
    assert bench.read(0x5400, 0) == 0x12000000
    assert (bench.fc.al_state, bench.fc.al_status_code) == (AlState.PREOP, 0x8012)
