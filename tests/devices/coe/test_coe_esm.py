"""The drive's EtherCAT state machine (seed 004 ch. 5 "Stati macchina", "Transizioni"; AL status
codes of seed 000 §7.7; ETG.1000.6 transitions; ETG.1300 indicators as ch. 5 refers to them).
"""

from __future__ import annotations

import json
import random

import pytest
from coe_bench import CIA402_ENABLE, make_bench, with_master

from devices.coe.drive_slave import DriveEcatSlave
from devices.coe.mailbox import MailboxClosed
from devices.ethercat import AlState
from devices.master import EtherCatMaster

INIT, PREOP, SAFEOP, OP = AlState.INIT, AlState.PREOP, AlState.SAFEOP, AlState.OP
BOOT = AlState.BOOT
PATH = {INIT: (), PREOP: (PREOP,), SAFEOP: (PREOP, SAFEOP), OP: (PREOP, SAFEOP, OP)}

# (from, requested) -> AL status code of the refusal; every other pair is accepted.
# ETG.1000.6: no skipping upwards; ch. 5: "BOOT ... Nota: non presente nel drive", and its
# drawing enters Bootstrap from Init only: ETG.1000.6 gives 0x0013 "Bootstrap not supported" to
# INIT -> BOOT, a BOOT request from PREOP / SAFEOP / OP is an invalid transition (0x0011).
REFUSED = {
    (INIT, SAFEOP): 0x0011, (INIT, OP): 0x0011, (PREOP, OP): 0x0011,
    (INIT, BOOT): 0x0013, (PREOP, BOOT): 0x0011, (SAFEOP, BOOT): 0x0011, (OP, BOOT): 0x0011,
}


@pytest.mark.parametrize("start", [INIT, PREOP, SAFEOP, OP])
@pytest.mark.parametrize("target", [INIT, PREOP, SAFEOP, OP, BOOT])
def test_requests_accepted_or_refused_with_the_al_code(start: AlState, target: AlState) -> None:
    bench = make_bench()
    bench.go(*PATH[start])
    assert bench.slave.al_state is start
    bench.go(target)
    code = REFUSED.get((start, target))
    if code is None:
        assert (bench.slave.al_state, bench.slave.al_status) == (target, int(target))
        assert bench.slave.al_status_code == 0
    else:
        # A refusal in OP lands in SAFEOP (ETG.1000.6; SSC AL_ControlInd, SOES ESC_state;
        # ch. 5 lists "Error SafeOp", no "Error Op").
        left = SAFEOP if start is OP else start
        assert bench.slave.al_state is left
        assert bench.slave.al_status == int(left) | 0x10  # error indication
        assert bench.slave.al_status_code == code


def test_a_refusal_is_acknowledged_by_requesting_the_current_state() -> None:
    bench = make_bench()
    bench.go(INIT, OP)
    assert bench.slave.al_status == 0x11
    bench.go(INIT)
    assert (bench.slave.al_status, bench.slave.al_status_code) == (0x01, 0)


def test_esm_events_carry_the_drive_id_and_the_esm_machine() -> None:
    bench = make_bench()
    bench.go(PREOP, SAFEOP, OP, OP, BOOT)
    states = [(e["device"], e["from"], e["to"], e["machine"]) for e in bench.kinds("state")
              if e.get("machine") == "esm"]
    assert states == [("servo", "INIT", "PREOP", "esm"), ("servo", "PREOP", "SAFEOP", "esm"),
                      ("servo", "SAFEOP", "OP", "esm"), ("servo", "OP", "SAFEOP", "esm")]
    assert [e["code"] for e in bench.kinds("al_status")] == ["0x0011"]


def test_mailbox_only_from_preop() -> None:
    """Ch. 5: INIT "Nessuna comunicazione con AL"; PREOP "Disponibile la comunicazione via
    Mailbox (SDO)"."""
    bench = make_bench()
    with pytest.raises(MailboxClosed):
        bench.read(0x1018, 1)
    bench.go(PREOP)
    assert bench.read(0x1018, 1) == 0x0000078F
    bench.go(INIT)
    with pytest.raises(MailboxClosed):
        bench.read(0x1018, 1)


def test_inputs_valid_from_safeop_outputs_applied_only_in_op() -> None:
    """Ch. 5: PREOP no process data; SAFEOP "disponibile solo per gli input"; OP both."""
    bench = make_bench()
    bench.go(PREOP)
    bench.slave.write_outputs(b"\x06\x00\x00\x00\x00\x00")
    bench.run(2)
    assert bench.slave.read_inputs() is None
    bench.go(SAFEOP)
    bench.run(2)
    assert bench.inputs("<Hi") == (bench.drive.statusword, bench.drive.position_user)
    assert bench.drive.cw == 0  # outputs not applied in SAFEOP
    bench.go(OP)
    bench.run(2)
    assert bench.drive.cw == 0x0006
    assert bench.drive.state.label == "Ready to switch on"


def test_safeop_to_op_needs_process_data_from_the_master() -> None:
    bench = make_bench()
    bench.cycling = False
    bench.run(150)  # the last frame is older than the SM watchdog time
    bench.go(PREOP, SAFEOP, OP)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (SAFEOP, 0x0019)
    bench.cycling = True
    bench.run(1)
    bench.go(OP)
    assert bench.slave.al_state is OP


def test_sm_watchdog_drops_to_safeop_and_raises_alarm_34() -> None:
    """No process data in OP for the SM watchdog time (100 ms): SAFEOP + 0x001B, error LED
    double flash (ETG.1300), and the drive's alarm 34 "Timeout sincronizzazione con il Master
    ECAT" (ch. 5) with its 0x603F code 0x8700."""
    bench = make_bench()
    bench.go(PREOP, SAFEOP, OP)
    bench.cycling = False
    bench.run(100)
    assert bench.slave.al_state is OP
    bench.run(2)
    assert (bench.slave.al_state, bench.slave.al_status) == (SAFEOP, 0x14)
    assert bench.slave.al_status_code == 0x001B
    assert bench.slave.leds.patterns["Error"].value == "double_flash"
    assert bench.drive.alarms.latched == [34]
    assert bench.read(0x603F) == 0x8700


def test_leaving_op_under_process_data_control_stops_the_drive() -> None:
    bench = make_bench()
    bench.up_to(OP)
    for value in CIA402_ENABLE:
        bench.outputs("<Hi", value, 0, ms=2)
    assert bench.drive.state.label == "Operation enabled"
    bench.go(SAFEOP)
    bench.run(300)
    assert bench.drive.state.label == "Switch on disabled"  # quick stop, then released


@pytest.mark.parametrize("request_", ("boot", "unknown"))
def test_a_request_refused_in_op_drops_to_safeop_and_stops_the_drive(request_: str) -> None:
    """ETG.1000.6 (SSC AL_ControlInd, SOES ESC_state; ch. 5 lists "Error SafeOp", no
    "Error Op"): a request refused in OP (BOOT, entered from INIT only: 0x0011; an
    unknown state: 0x0012) leaves the slave in SAFEOP + error, and a drive under process-data
    control stops as on any way out of OP."""
    bench = make_bench()
    bench.up_to(OP)
    for value in CIA402_ENABLE:
        bench.outputs("<Hi", value, 0, ms=2)
    assert bench.drive.state.label == "Operation enabled"
    if request_ == "boot":
        bench.slave.request_state(BOOT)
    else:  # AL control 0x05, as the wire face hands it to the ESM
        bench.slave.esm.request_unknown(0x05, False, bench.t_us)
    bench.step()
    code = 0x0011 if request_ == "boot" else 0x0012
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (SAFEOP, 0x14, code)
    assert slave.leds.snapshot()["Error"] == "blinking"  # ETG.1300: refused
    bench.run(300)
    assert bench.drive.state.label == "Switch on disabled"  # quick stop, then released


def test_leaving_op_without_process_data_control_leaves_the_drive_alone() -> None:
    bench = make_bench()
    bench.up_to(PREOP)
    bench.cw(*CIA402_ENABLE)
    bench.go(SAFEOP, OP, SAFEOP)
    bench.run(50)
    assert bench.drive.state.label == "Operation enabled"


@pytest.mark.parametrize(("state", "pattern"), [
    (INIT, "off"), (PREOP, "blinking"), (SAFEOP, "single_flash"), (OP, "on")])
def test_status_led_follows_the_esm(state: AlState, pattern: str) -> None:
    """Ch. 5: Status "Se sempre acceso ethercat è in operational mode" (ETG.1300 RUN)."""
    bench = make_bench()
    bench.go(*PATH[state])
    bench.run(1)
    assert bench.slave.leds.snapshot()["Status"] == pattern


def test_error_led_blinks_on_a_refusal() -> None:
    bench = make_bench()
    bench.go(PREOP, OP)
    assert bench.slave.leds.snapshot()["Error"] == "blinking"


# Ch. 5: Error "La frequenza di lampeggio è funzione della tipologia di allarme ... ETG-1300":
# ETG.1300 ERR by the alarm's kind. On = application controller failure (7 DSP in fault,
# 30-32 the drive's internal communication), flickering = booting error (35 EtherCAT EEPROM
# load, in INIT: test_coe_booting_error.py); an alarm of the motor or the axis leaves
# EtherCAT in working order: off (it is on the display and in 0x603F, ch. 5 "Codici allarmi
# specifici"). docs/ethercat-coe.md §LEDs.
@pytest.mark.parametrize(("code", "pattern"), [
    (2, "off"), (3, "off"), (16, "off"), (7, "on"), (30, "on"), (31, "on"), (32, "on"),
    (35, "flickering")])
def test_error_led_follows_the_kind_of_drive_alarm(code: int, pattern: str) -> None:
    bench = make_bench()
    bench.go(PREOP)
    bench.drive.apply("inject_alarm", {"code": str(code)})
    bench.run(1)
    assert bench.drive.alarms.latched == [code]
    assert bench.slave.leds.snapshot()["Error"] == pattern


def test_an_application_controller_failure_outranks_an_esm_error() -> None:
    """A refused request (blinking) with alarm 7 latched: ON, the most severe ERR row."""
    bench = make_bench()
    bench.go(PREOP, OP)
    bench.drive.apply("inject_alarm", {"code": "7"})
    bench.run(1)
    assert bench.slave.leds.snapshot()["Error"] == "on"


# Ch. 5 "Codici allarmi specifici": 7 "Processore DSP in fault" and 30-32 the drive's internal
# communication: the controller that makes the process data (statusword, positions) is gone
# behind the EtherCAT interface. The interface keeps its mailbox (PREOP: 0x603F and the
# emergency are how the table's codes reach the master, "Reset allarmi" goes "via coe"), but
# no input or output can be valid: ETG.1000.6 0x002B "No Valid Inputs and Outputs", O / S ->
# PREOP + error. docs/ethercat-coe.md "Drive alarms and the EtherCAT side".
CONTROLLER_ALARMS = {7: 0x5220, 30: 0x1000, 31: 0x7500, 32: 0x7500}


@pytest.mark.parametrize(("code", "error_code"), CONTROLLER_ALARMS.items())
@pytest.mark.parametrize("start", [SAFEOP, OP])
def test_a_controller_alarm_drops_the_slave_to_preop_with_0x002b(
        start: AlState, code: int, error_code: int) -> None:
    bench = make_bench()
    bench.up_to(start)
    bench.drive.apply("inject_alarm", {"code": str(code)})
    bench.run(1)
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (PREOP, 0x12, 0x002B)
    assert slave.read_inputs() is None
    assert slave.leds.snapshot() == {"L/A IN": "flickering", "Status": "blinking",
                                     "L/A OUT": "off", "Error": "on"}
    assert bench.read(0x603F) == error_code  # the mailbox still answers
    assert [frame[:2] for frame in bench.emergencies] == [error_code.to_bytes(2, "little")]
    assert bench.kinds("al_status")[-1]["code"] == "0x002B"
    assert bench.kinds("state")[-1]["to"] == "PREOP"
    assert any(f"alarm {code}" in e["text"] and "0x002B" in e["text"]
               for e in bench.kinds("log"))


def test_after_the_reset_err_shows_the_local_error_until_the_master_acknowledges() -> None:
    """ETG.1300: ERR on while the controller alarm lasts; once it is reset the fall itself is
    left, "local error" (single flash: the slave changed its state on its own), with the error
    flag and 0x002B, until the master requests a state (acknowledge)."""
    bench = make_bench()
    bench.up_to(OP)
    bench.drive.apply("inject_alarm", {"code": "30"})
    bench.run(1)
    bench.drive.apply("clear_alarm", {"code": "30"})
    bench.cw(0x0080, 0x0000)
    assert bench.drive.alarms.latched == []
    assert (bench.slave.al_status, bench.slave.al_status_code) == (0x12, 0x002B)
    assert bench.slave.leds.snapshot()["Error"] == "single_flash"
    bench.go(PREOP)
    assert (bench.slave.al_status, bench.slave.al_status_code) == (0x02, 0)
    assert bench.slave.leds.snapshot()["Error"] == "off"


@pytest.mark.parametrize("code", [7, 30, 31, 32])
def test_safeop_refused_while_a_controller_alarm_is_latched_then_reset_over_coe(
        code: int) -> None:
    """Ch. 5 "Reset allarmi": "via coe ... scrittura 0x80 su oggetto 0x6040" in PREOP. 30 too:
    ch. 6's "Resettabile NO" is Profinet's (docs/ethercat-coe.md "7 and 30-32 are resettable
    on EtherCAT")."""
    bench = make_bench()
    bench.up_to(PREOP)
    bench.drive.apply("inject_alarm", {"code": str(code)})
    bench.run(1)
    assert bench.slave.al_state is PREOP and bench.slave.al_status_code == 0
    bench.go(SAFEOP)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (PREOP, 0x002B)
    assert bench.slave.leds.snapshot()["Error"] == "on"
    bench.cw(0x0080, 0x0000)
    bench.go(SAFEOP)
    assert bench.slave.al_status_code == 0x002B  # the cause is still there
    bench.drive.apply("clear_alarm", {"code": str(code)})
    bench.cw(0x0080, 0x0000)
    assert bench.drive.alarms.latched == []
    bench.go(PREOP, SAFEOP, OP)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (OP, 0)
    assert bench.slave.leds.snapshot()["Error"] == "off"


@pytest.mark.parametrize("code", [1, 2, 5, 9, 16, 20, 26])
def test_a_drive_alarm_leaves_the_esm_in_op(code: int) -> None:
    """ETG.6010: a fault of the drive is the CiA 402 Fault, 0x603F and the emergency; the ESM
    stays in OP so the master can read and reset it through the process data."""
    bench = make_bench()
    bench.up_to(OP)
    bench.drive.apply("inject_alarm", {"code": str(code)})
    bench.run(5)
    assert bench.drive.state.label == "Fault"
    assert (bench.slave.al_state, bench.slave.al_status_code) == (OP, 0)
    assert bench.inputs("<Hi")[0] & 0x0008  # statusword bit 3 Fault, through the process data


def test_the_built_in_master_keeps_a_controller_alarm_in_preop_until_reset() -> None:
    bench = make_bench()
    _, run = with_master(bench)

    run(1000)
    assert bench.slave.al_state is OP
    bench.drive.apply("inject_alarm", {"code": "7"})
    run(1000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (PREOP, 0x002B)
    bench.drive.apply("clear_alarm", {"code": "7"})
    bench.write(0x6040, 0, 0x0080, 2)
    bench.write(0x6040, 0, 0x0000, 2)
    run(1000)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (OP, 0)


def test_silent_unless_c9_was_ethercat_at_power_up() -> None:
    """Ch. 5: "Parametro drive C9 = 11 (modalità ethercat)", read at power-up (ch. 2, 4)."""
    bench = make_bench(fieldbus="modbus")
    assert not bench.slave.reachable()
    bench.go(PREOP)
    assert bench.slave.al_state is INIT
    # Its ESC is powered: L/A IN shows the link (on: no frame passed it here; ETG.1300 L/A
    # are the ESC's), Status stays dark (no EtherCAT application; until session 20 all dark)
    leds = bench.slave.leds.snapshot()
    assert (leds["L/A IN"], leds["Status"]) == ("on", "off")
    bench.drive.apply("write_parameter", {"parameter": "c9", "value": 11})
    bench.run(1)
    assert not bench.slave.reachable()  # latched at power-up only
    bench.drive.apply("save", {})
    bench.run(3100)
    bench.drive.apply("power", {"on": False})
    bench.run(1)
    bench.drive.apply("power", {"on": True})
    bench.run(60)
    assert bench.slave.reachable()
    bench.go(PREOP)
    assert bench.slave.al_state is PREOP


def test_power_off_takes_the_slave_to_init_and_power_on_restores_the_defaults() -> None:
    bench = make_bench()
    bench.go(PREOP)
    bench.write(0x1C13, 0, 0, 1)
    bench.go(SAFEOP, OP)
    bench.drive.apply("power", {"on": False})
    bench.run(1)
    assert (bench.slave.al_state, bench.slave.reachable()) == (INIT, False)
    bench.drive.apply("power", {"on": True})
    bench.run(60)
    bench.go(PREOP)
    assert bench.read(0x1C13, 0) == 1


def test_pulled_cable_the_master_loses_the_slave_and_brings_it_back() -> None:
    """With the built-in master: the slave in OP, the cable pulled, the SM watchdog drops it to
    SAFEOP; with the cable back the master finds it in SAFEOP and takes it back to OP."""
    bench = make_bench()
    master = EtherCatMaster("master", random.Random(1), slaves=[bench.slave],
                            retry_interval_us=200_000)
    bench.cycling = False  # the master's frames now
    for _ in range(1000):
        bench.step()
        master.step(bench.t_us)
    assert bench.slave.al_state is OP
    assert bench.slave.station_address == 1001
    bench.slave.apply("link", {"connected": False})
    for _ in range(200):
        bench.step()
        master.step(bench.t_us)
    assert bench.slave.al_state is SAFEOP and bench.slave.al_status_code == 0x001B
    bench.slave.apply("link", {"connected": True})
    for _ in range(1000):
        bench.step()
        master.step(bench.t_us)
    assert bench.slave.al_state is OP
    assert bench.drive.alarms.latched == [34]  # the drive still shows why it stopped


@pytest.mark.parametrize("reset_by", ["sdo", "outputs"])
def test_alarm_34_stays_latched_after_the_recovery_until_a_reset_over_coe(reset_by: str) -> None:
    """Seed 004 ch. 5 "Reset allarmi" (l. 4870-4874): an alarm is reset "via coe ... scrittura
    0x80 su oggetto 0x6040"; nothing in ch. 3 / 5 / 6 clears one by itself, and ch. 6 gives the
    same sync timeout "Resettabile SI" (l. 5290). So the line back in OP does not clear 34: the
    drive keeps its display, 0x603F and the Fault bit until the reset, then the error reset."""
    bench = make_bench()
    bench.go(PREOP, SAFEOP, OP)
    bench.outputs("<Hi", 0x0000, 0)
    bench.cycling = False
    bench.run(150)
    assert bench.drive.alarms.latched == [34]
    bench.cycling = True
    bench.run(5)
    bench.go(SAFEOP, OP)  # the master acknowledges and takes it up again
    bench.run(500)
    slave = bench.slave
    assert (slave.al_state, slave.al_status, slave.al_status_code) == (OP, 0x08, 0)
    assert slave.leds.patterns["Error"].value == "off"
    assert bench.drive.alarms.latched == [34]  # no reset yet: still latched
    assert bench.read(0x603F) == 0x8700
    assert bench.inputs("<Hi")[0] & 0x0008  # statusword bit 3, Fault
    if reset_by == "sdo":
        bench.cw(0x0080)
    else:
        bench.outputs("<Hi", 0x0080, 0, ms=5)
    bench.run(5)
    assert bench.drive.alarms.latched == []
    assert bench.read(0x603F) == 0
    assert bench.emergencies[-1][:3] == b"\x00\x00\x00"  # DS 301 error reset

def test_slave_protocol_of_the_master() -> None:
    slave: DriveEcatSlave = make_bench().slave
    assert slave.box_name == "Drive 1 (SelemaDriveECAT)"
    assert slave.reachable() and slave.al_state is INIT and slave.take_emergencies() == []


def test_snapshot_is_plain_data() -> None:
    bench = make_bench()
    bench.up_to(OP)
    snap = json.loads(json.dumps(bench.slave.snapshot()))
    assert (snap["esm"], snap["slot"], snap["rx_assign"], snap["tx_assign"]) == \
        ("OP", "interpolated", ["0x1600"], ["0x1A02"])
    assert snap["inputs"] == "40 86 00 00 00 00"  # 0x8640, the fresh drive's statusword
    assert make_bench(fieldbus="canopen").slave.snapshot()["esm"] == "Off"
