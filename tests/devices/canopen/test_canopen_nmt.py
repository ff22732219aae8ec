"""NMT slave: boot-up, the state table, services per state, power and c9 (seed 004 ch. 4).

Sections: "CANopen network management (NMT)", "Stati e Cambiamento di stato", "Configurazione
della rete" (c7, c9, n1 read at power-up only).
"""

from __future__ import annotations

import pytest
from canopen_bench import h, hexs, make_bench

from devices.canopen.nmt import TRANSITIONS, NmtCommand, NmtState

REACH = {  # commands that bring a fresh node (Pre-operational) into a state
    NmtState.PRE_OPERATIONAL: (),
    NmtState.OPERATIONAL: (NmtCommand.START,),
    NmtState.STOPPED: (NmtCommand.STOP,),
}


def test_boot_up_message_then_pre_operational() -> None:
    """"il nodo trasmette il cosiddetto boot-up message e si pone allo stato Pre-Operational";
    "Il byte di dati del messaggio di avvio ha il valore 0x00"; COB-ID 1792 + node-ID."""
    bench = make_bench(node_id=5, boot=False)
    bench.run(60)
    boots = [f for f in bench.take() if f.can_id == 0x705]
    assert [hexs(f.data) for f in boots] == ["00"]
    assert 50_000 <= boots[0].t_us <= 52_000
    assert bench.node.state is NmtState.PRE_OPERATIONAL
    assert bench.kinds("state")[-1] == {"t": pytest.approx(0.051), "device": "servo",
                                        "event": "state", "from": "Initialisation",
                                        "to": "Pre-operational", "machine": "nmt"}


@pytest.mark.parametrize(("start", "command"), sorted(TRANSITIONS, key=str))
def test_transition_table(start: NmtState, command: NmtCommand) -> None:
    """Every (state, command) of the table, commanded on CAN-ID 0 with two bytes."""
    bench = make_bench()
    for step in REACH[start]:
        bench.nmt(step)
    assert bench.node.state is start
    bench.nmt(command)
    expected = TRANSITIONS[(start, command)]
    if expected is NmtState.INITIALISATION:
        assert bench.node.state is NmtState.INITIALISATION
        bench.run(60)  # Initialisation ends with a boot-up message
        assert hexs(bench.take()[-1].data) == "00"
        expected = NmtState.PRE_OPERATIONAL
    assert bench.node.state is expected


@pytest.mark.parametrize(("data", "moves"), [
    ("01 01", True),  # to this node
    ("01 00", True),  # "nodo virtuale-ID 0": every node
    ("01 02", False),  # another node
    ("01", False),  # one byte: not an NMT frame
    ("01 01 00", False),  # three bytes
    ("03 01", False),  # no such command
])
def test_command_addressing(data: str, moves: bool) -> None:
    bench = make_bench()
    bench.send(0x000, h(data))
    bench.run(2)
    assert (bench.node.state is NmtState.OPERATIONAL) is moves


@pytest.mark.parametrize(("state", "sdo", "pdo", "sync"), [
    (NmtState.PRE_OPERATIONAL, True, False, True),
    (NmtState.OPERATIONAL, True, True, True),
    (NmtState.STOPPED, False, False, False),
])
def test_services_per_state(state: NmtState, sdo: bool, pdo: bool, sync: bool) -> None:
    """Pre-operational: SDO, SYNC, no PDO; Operational: PDOs too; Stopped: only NMT and
    guarding / heartbeat."""
    bench = make_bench()
    bench.ok(0x100C, 0, 100, 2)  # guard time: remote requests get answers
    for step in REACH[state]:
        bench.nmt(step)
    answer = bench.request(0x601, h("40 41 60 00 00 00 00 00"), 0x581, timeout_ms=10)
    assert (answer is not None) is sdo
    syncs = bench.node.syncs
    bench.send(0x080)
    bench.run(2)
    assert (bench.node.syncs > syncs) is sync
    bench.send(0x201, h("06 00 00 00 00 00"))  # RPDO1: controlword 0x0006 + set-point
    bench.run(5)
    assert (bench.drive.cw == 0x0006) is pdo
    bench.take()
    bench.send(0x701, rtr=True, dlc=1)  # node guarding answers in every state
    bench.run(2)
    assert [hexs(f.data) for f in bench.take()] == [f"{state.code:02X}"]


def test_not_on_canopen_the_node_is_silent() -> None:
    """c9 = 3 (Modbus) at power-up: no boot-up, no answers."""
    bench = make_bench(fieldbus="modbus")
    assert bench.take() == []
    assert bench.request(0x601, h("40 18 10 01 00 00 00 00"), timeout_ms=20) is None
    assert bench.node.snapshot()["nmt"] == "Off"


def test_power_cycle_boots_again_with_the_latched_node_id() -> None:
    """c7 is read at power-up only: a new node number (saved) takes effect after a power
    cycle."""
    bench = make_bench(node_id=3)
    bench.drive.apply("write_parameter", {"parameter": "c7", "value": 9})
    bench.drive.apply("save", {})
    bench.run_until(lambda: bench.drive.save_done, 5_000)
    assert bench.request(0x603, h("40 18 10 01 00 00 00 00"), 0x583) is not None
    bench.drive.apply("power", {"on": False})
    bench.run(5)
    assert bench.request(0x603, h("40 18 10 01 00 00 00 00"), timeout_ms=20) is None
    bench.take()
    bench.drive.apply("power", {"on": True})
    bench.run(60)
    assert [f.can_id for f in bench.take()] == [0x709]
    assert bench.request(0x609, h("40 18 10 01 00 00 00 00"), 0x589) is not None


def test_reset_node_restores_power_on_values_reset_communication_keeps_them() -> None:
    """Reset-Application: profile values back to power-on (last saved); Reset-Communication:
    only the communication objects."""
    bench = make_bench()
    bench.ok(0x6081, 0, 12345, 4)
    bench.ok(0x1017, 0, 500, 2)
    bench.nmt(NmtCommand.RESET_COMMUNICATION)
    bench.run(10)
    assert bench.read(0x1017) == 0
    assert bench.read(0x6081) == 12345
    bench.ok(0x1017, 0, 500, 2)
    bench.nmt(NmtCommand.RESET_NODE)
    bench.run(60)
    assert bench.node.state is NmtState.PRE_OPERATIONAL
    assert bench.read(0x1017) == 0
    assert bench.read(0x6081) != 12345


def test_reset_communication_keeps_the_device_profile_objects_of_the_node() -> None:
    """"Reset-Comunicazione": "i parametri del profilo di comunicazione sono riportati ai
    valori di Power-On" (ch. 4 "Stati e Cambiamento di stato"); 0x67FF (single device type,
    rw in the ch. 4 table) is a device profile object (0x6000-0x9FFF, "Standardised Device
    Profile Area"), so it keeps its value, as 0x6081 does; Reset node brings back its
    power-on value (Reset-Application). Before, Reset communication rebuilt it."""
    bench = make_bench()
    bench.ok(0x67FF, 0, 0x0004_0192, 4)
    bench.nmt(NmtCommand.RESET_COMMUNICATION)
    bench.run(10)
    assert bench.read(0x67FF) == 0x0004_0192
    bench.nmt(NmtCommand.RESET_NODE)
    bench.run(80)
    assert bench.read(0x67FF) == 0x0002_0192


@pytest.mark.parametrize("restart", ["reset node", "power cycle"])
def test_objects_outside_the_save_list_come_back_at_their_power_on_value(restart: str) -> None:
    """0x60F8 (max slippage, rw) is not among the objects a save keeps (ch. 4 "Salvataggio
    su flash" lists them; 0x60F8 is not there), so a save does not keep it and "Reset-
    Application" ("ripristinati ai valori di Power-On (corrisponde agli ultimi valori
    salvati)") or a power cycle brings back its power-on value, as 0x607A's. Before, the
    value written stayed in the dictionary through both."""
    bench = make_bench()
    bench.ok(0x60F8, 0, 4242, 4)
    bench.ok(0x607A, 0, 4242, 4)
    bench.ok(0x1010, 1, 0x65766173, 4)
    bench.run_until(lambda: bench.drive.save_done, 5_000)
    if restart == "reset node":
        bench.nmt(NmtCommand.RESET_NODE)
    else:
        bench.drive.apply("power", {"on": False})
        bench.run(5)
        bench.drive.apply("power", {"on": True})
    bench.run(80)
    assert bench.node.state is NmtState.PRE_OPERATIONAL
    assert (bench.read(0x60F8), bench.read(0x607A)) == (0, 0)


@pytest.mark.parametrize("start", sorted(REACH, key=str))
def test_power_off_reports_the_nmt_change(start: NmtState) -> None:
    """A node that falls silent with its drive reports it like every NMT change: the event
    stream must not keep the old state (the recording's NMT lane and the event log follow
    it). Power-off is Initialisation's vocabulary, as the drive's DS402 machine and the CoE
    slave's ESM fall to their power-on states; the snapshot shows "Off"."""
    bench = make_bench()
    for step in REACH[start]:
        bench.nmt(step)
    before = len(bench.kinds("state"))
    bench.drive.apply("power", {"on": False})
    bench.run(2)
    assert bench.node.snapshot()["nmt"] == "Off"
    nmt = [e for e in bench.kinds("state")[before:] if e.get("machine") == "nmt"]
    assert [(e["from"], e["to"]) for e in nmt] == [(start.label, "Initialisation")]
    bench.drive.apply("power", {"on": True})
    bench.run(60)  # power-up: Initialisation already, then boot-up -> Pre-operational
    nmt = [e for e in bench.kinds("state")[before:] if e.get("machine") == "nmt"]
    assert [(e["from"], e["to"]) for e in nmt][1:] == [("Initialisation", "Pre-operational")]
