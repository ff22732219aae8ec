"""PDO mapping rules and transmission types (seed 004 ch. 4 "Note sui servizi ... Servizio SDO"
(mapping rules), "Servizio PDO" (types), "Process data exchange with PDOs", and the
interpolator example "Modo interpolatore" with its SYNC + RPDO loop).
"""

from __future__ import annotations

import itertools
import struct

import pytest
from canopen_bench import CANOPEN_ENABLE, hexs, make_bench

from devices.canopen.nmt import NmtCommand

OK = "ok"


def _abort(answer: str) -> str:
    if answer.startswith("60"):
        return OK
    assert answer.startswith("80"), answer
    return f"0x{int.from_bytes(bytes.fromhex(answer)[4:8], 'little'):08X}"


@pytest.mark.parametrize(("writes", "result"), [
    # the seed's interpolator mapping (1600) and feedback mapping (1A00, sub 2 for the second)
    ([(0x1600, 0, 0, 1), (0x1600, 1, 0x60C10120, 4), (0x1600, 2, 0x60400010, 4),
      (0x1600, 0, 2, 1)], OK),
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640020, 4), (0x1A00, 2, 0x60410010, 4),
      (0x1A00, 0, 2, 1)], OK),
    # as printed ("1A00, sub 1" twice): sub 2 stays empty, so two entries cannot be enabled
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640020, 4), (0x1A00, 1, 0x60410010, 4),
      (0x1A00, 0, 2, 1)], "0x06040041"),
    # an entry while the PDO has entries: NumOfEntries to 0 first
    ([(0x1A00, 1, 0x60640020, 4)], "0x06010000"),
    # existence, mappability, direction, length
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x50000020, 4)], "0x06040041"),
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x20000108, 4)], "0x06040041"),  # 0x2000:1 "NO map."
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60410020, 4)], "0x06040041"),  # SW is 16 bits
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60600008, 4)], "0x06040041"),  # wo object in a TPDO
    ([(0x1600, 0, 0, 1), (0x1600, 1, 0x60410010, 4)], "0x06040041"),  # ro object in an RPDO
    # "una lunghezza massima di 8 Byte": 12 bytes refused when enabled
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640020, 4), (0x1A00, 2, 0x606C0020, 4),
      (0x1A00, 3, 0x60690020, 4), (0x1A00, 0, 3, 1)], "0x06040042"),
    ([(0x1A00, 0, 9, 1)], "0x06090031"),
    # DS 301 dummy entries: RPDO only
    ([(0x1600, 0, 0, 1), (0x1600, 1, 0x00050008, 4), (0x1600, 2, 0x60400010, 4),
      (0x1600, 0, 2, 1)], OK),
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x00050008, 4)], "0x06040041"),
])
def test_mapping_rules(writes: list[tuple[int, int, int, int]], result: str) -> None:
    bench = make_bench()
    answers = [_abort(bench.write(index, sub, value, size)) for index, sub, value, size in writes]
    assert answers[:-1] == [OK] * (len(writes) - 1)
    assert answers[-1] == result


def _tpdos(bench, can_id: int = 0x181) -> list:
    return [f for f in bench.take() if f.can_id == can_id]


def _started(**kw) -> object:
    bench = make_bench(**kw)
    bench.nmt(NmtCommand.START)
    bench.run(5)
    bench.take()
    return bench


@pytest.mark.parametrize("n", [1, 2, 4])
def test_synchronous_cyclic_every_n_syncs(n: int) -> None:
    """"Se Type vale n, compreso tra 1 e 240, il TPDO ... viene spedito ogni n Sync"."""
    bench = make_bench()
    bench.ok(0x1800, 2, n, 1)
    bench.nmt(NmtCommand.START)
    bench.take()
    for _ in range(8):
        bench.send(0x080)
        bench.run(5)
    frames = _tpdos(bench)
    assert len(frames) == 8 // n
    assert all(hexs(f.data) == "40 86" for f in frames)  # statusword 0x8640: switch on disabled


def test_synchronous_tpdo_carries_the_values_of_the_sync_that_sends_it() -> None:
    """A synchronous TPDO's data are sampled at the SYNC that sends it, not at the one before:
    ch. 4 "Position feedback e StatusWord verranno trasmessi dal drive ad ogni Sync" and the
    note "[0x6064] viene aggiornato internamente ogni ms. L'istante in cui la posizione viene
    campionata ha dunque un'incertezza pari ad 1 ms" (CiA 301 alike). The generic
    introduction's "i consumatori ricevono le variabili di processo catturate al Sync
    precedente" is not this drive's behaviour (docs/canopen.md §PDOs)."""
    bench = make_bench()
    bench.ok(0x1800, 2, 1, 1)
    bench.nmt(NmtCommand.START)
    bench.send(0x080)
    bench.run(5)
    assert [hexs(f.data) for f in _tpdos(bench)] == ["40 86"]  # switch on disabled
    bench.ok(0x6040, 0, 0x0006, 2)  # shutdown: ready to switch on, between two SYNCs
    bench.run(5)
    bench.take()
    bench.send(0x080)
    bench.run(5)
    # the state at this SYNC: 0x0621, ready to switch on as ch. 5's TwinCAT screen shows it
    assert [hexs(f.data) for f in _tpdos(bench)] == ["21 06"]


@pytest.mark.parametrize("trans_type", [0, 1, 4])
def test_remote_request_for_a_synchronous_tpdo_gets_the_values_of_the_last_sync(
        trans_type: int) -> None:
    """Seed 004 ch. 4 (l. 2218-2222): the device records its inputs at every SYNC, sent or
    not, "in quanto può accadere che le variabili di processo sincrono registrati in un PDO
    vengono richiesti da RTR. In questo caso il dispositivo CANopen deve trasmettere il PDO
    corrispondente con i valori rilevati" at that SYNC: a change after the SYNC is not in the
    answer. Before the first SYNC nothing is recorded: the values of that instant."""
    bench = make_bench()
    bench.ok(0x1800, 2, trans_type, 1)
    bench.nmt(NmtCommand.START)
    bench.run(5)
    bench.send(0x181, rtr=True, dlc=2)
    bench.run(2)
    assert [hexs(f.data) for f in _tpdos(bench)] == ["40 86"]  # no SYNC yet: this instant
    bench.send(0x080)
    bench.run(5)
    bench.take()
    bench.ok(0x6040, 0, 0x0006, 2)  # shutdown after the SYNC: ready to switch on
    bench.run(5)
    bench.take()
    bench.send(0x181, rtr=True, dlc=2)
    bench.run(2)
    assert [hexs(f.data) for f in _tpdos(bench)] == ["40 86"]  # recorded at the SYNC
    for _ in range(trans_type or 1):  # type n: SYNCs that do not send it still record
        bench.send(0x080)
        bench.run(5)
    bench.take()
    bench.send(0x181, rtr=True, dlc=2)
    bench.run(2)
    assert [hexs(f.data) for f in _tpdos(bench)] == ["21 06"]  # ready to switch on: 0x0621 (ch. 5)


@pytest.mark.parametrize(("index", "trans_type", "result"), [
    (0x1800, 0, OK), (0x1800, 240, OK), (0x1800, 254, OK), (0x1800, 255, OK),
    (0x1800, 241, "0x06090030"), (0x1800, 251, "0x06090030"),
    (0x1800, 252, "0x06090030"), (0x1800, 253, "0x06090030"),
    (0x1803, 252, "0x06090030"), (0x1400, 252, "0x06090030"), (0x1400, 253, "0x06090030"),
])
def test_transmission_types_the_drive_has(index: int, trans_type: int, result: str) -> None:
    """The drive's types (ch. 4 "Servizio PDO": 0, 1..240, 254/255; "Modi PDO: sincrono
    (ciclico e aciclico), asincrono"): the RTR-only 252/253 of the generic table and the
    reserved 241..251 are refused with DS 301's "value range of parameter exceeded", and the
    type stays."""
    bench = make_bench()
    assert _abort(bench.write(index, 2, trans_type, 1)) == result
    assert bench.read(index, 2) == (trans_type if result == OK else 255)


def test_synchronous_acyclic_only_after_an_event() -> None:
    """Type 0: "viene inviato al Sync successivo il verificarsi di uno specifico evento"."""
    bench = make_bench()
    bench.ok(0x1800, 2, 0, 1)
    bench.nmt(NmtCommand.START)
    bench.take()
    counts = []
    for cw in (None, None, 0x0006, None):
        if cw is not None:
            bench.ok(0x6040, 0, cw, 2)
        bench.send(0x080)
        bench.run(5)
        counts.append(len(_tpdos(bench)))
    assert counts == [1, 0, 1, 0]


def test_asynchronous_event_timer() -> None:
    """Type 255 with an event timer: sent on the timer even without a change."""
    bench = make_bench()
    bench.ok(0x1800, 5, 100, 2)
    bench.nmt(NmtCommand.START)
    bench.take()
    bench.run(1_000)
    times = [f.t_us for f in _tpdos(bench)]
    assert len(times) in (10, 11)
    assert {b - a for a, b in itertools.pairwise(times)} == {100_000}


def test_event_timer_starts_when_written() -> None:
    """"Se viene scritto un valore maggiore di 0, il timer si attiva ... Allo scadere del
    timer viene trasmesso il PDO": a timer written long after the TPDO last went out sends
    it one period after the write, not at once."""
    bench = _started()
    bench.run(5_000)  # statusword steady: TPDO1 went out once, on entering Operational
    bench.take()
    bench.ok(0x1800, 5, 100, 2)
    written = bench.t_us
    bench.run(350)
    times = [f.t_us - written for f in _tpdos(bench)]
    assert len(times) == 3
    assert 99_000 <= times[0] <= 101_000
    assert {b - a for a, b in itertools.pairwise(times)} == {100_000}


def test_asynchronous_on_change_with_inhibit_time() -> None:
    """Sent on a change of the mapped data, never within the inhibit time (x 100 us) of the
    previous one: "deve essere passato un tempo superiore a InhibitTime"."""
    bench = make_bench()
    bench.ok(0x1801, 1, 0x281, 4)  # TPDO2: statusword + modes of operation display
    bench.ok(0x1801, 3, 200, 2)  # 20 ms
    bench.nmt(NmtCommand.START)
    bench.take()
    for i in range(20):  # a new mode every 5 ms
        bench.ok(0x6060, 0, (1, 3)[i % 2], 1)
        bench.run(3)
    times = [f.t_us for f in _tpdos(bench, 0x281)]
    assert len(times) >= 3
    assert min(b - a for a, b in itertools.pairwise(times)) > 20_000


def test_asynchronous_rpdo_applies_at_once_synchronous_at_the_next_sync() -> None:
    """"Se Type è uguale a 254 o 255 gli RPDO ... vengono attuati appena ricevuti";
    "0..240 ... al Sync immediatamente successivo alla loro ricezione"."""
    bench = _started()
    bench.send(0x201, struct.pack("<Hi", 0x0006, 0))
    bench.run(2)
    assert bench.drive.cw == 0x0006
    bench.nmt(NmtCommand.ENTER_PRE_OPERATIONAL)
    bench.ok(0x1400, 2, 1, 1)
    bench.nmt(NmtCommand.START)
    bench.send(0x201, struct.pack("<Hi", 0x0007, 0))
    bench.run(5)
    assert bench.drive.cw == 0x0006
    bench.send(0x080)
    bench.run(2)
    assert bench.drive.cw == 0x0007


def test_rpdo_is_taken_on_its_current_cob_id() -> None:
    """"Un nodo di rete che vuole accettare un certo PDO deve solo attivare il corrispondente
    messaggio CAN ... con la validazione del corrispondente COB-ID nel OD" and "PDO linking:
    Si": after 0x1400:1 = 513 node 2 takes RPDO1 on 0x201 (the interpolator note) and no
    longer on its default 0x202."""
    bench = _started(node_id=2)
    bench.nmt(NmtCommand.ENTER_PRE_OPERATIONAL)
    bench.ok(0x1400, 1, 513, 4)
    bench.nmt(NmtCommand.START)
    bench.send(0x202, struct.pack("<Hi", 0x0006, 0))  # the old COB-ID: not this PDO's now
    bench.run(3)
    assert bench.drive.cw == 0
    bench.send(0x201, struct.pack("<Hi", 0x0006, 0))
    bench.run(3)
    assert bench.drive.cw == 0x0006
    bench.ok(0x1400, 1, 0x202, 4)  # and back again
    bench.send(0x201, struct.pack("<Hi", 0x0007, 0))
    bench.run(3)
    assert bench.drive.cw == 0x0006
    bench.send(0x202, struct.pack("<Hi", 0x0007, 0))
    bench.run(3)
    assert bench.drive.cw == 0x0007


def test_rpdo_with_bit_31_set_is_ignored() -> None:
    """"Un MSB settato a 1 significa NON valido": RPDO2 (0x80000301 at power-on) takes
    nothing, not even a length error, until bit 31 is cleared; a synchronous RPDO switched
    off is not applied at the Sync either."""
    bench = _started()
    assert bench.read(0x1401, 1) == 0x8000_0301
    bench.send(0x301, struct.pack("<Hb", 0x0006, 3))
    bench.send(0x301, bytes((0x06,)))  # too short for its mapping: no EMCY 0x8210 either
    bench.run(3)
    assert (bench.drive.cw, bench.drive.mode) == (0, 1)
    assert [f for f in bench.take() if f.can_id == 0x081] == []
    bench.ok(0x1401, 1, 0x301, 4)
    bench.send(0x301, struct.pack("<Hb", 0x0006, 3))
    bench.run(3)
    assert (bench.drive.cw, bench.drive.mode) == (0x0006, 3)
    bench.ok(0x1400, 2, 1, 1)  # RPDO1 synchronous, then switched off
    bench.ok(0x1400, 1, 0x8000_0201, 4)
    bench.send(0x201, struct.pack("<Hi", 0x0007, 0))
    bench.send(0x080)
    bench.run(3)
    assert bench.drive.cw == 0x0006


def test_tpdo_goes_out_on_its_current_cob_id_and_not_when_switched_off() -> None:
    """0x1800:1 moves TPDO1 (timer, SYNC and remote request alike); bit 31 stops it."""
    bench = make_bench()
    bench.ok(0x1800, 5, 20, 2)
    bench.ok(0x1800, 1, 0x1A1, 4)
    bench.nmt(NmtCommand.START)
    bench.run(100)
    bench.send(0x1A1, rtr=True, dlc=2)
    bench.send(0x181, rtr=True, dlc=2)
    bench.run(2)
    frames = bench.take()
    assert len(_tpdos_in(frames, 0x1A1)) >= 5
    assert _tpdos_in(frames, 0x181) == []
    bench.ok(0x1800, 1, 0x8000_01A1, 4)
    bench.ok(0x1800, 2, 1, 1)
    bench.run(100)
    bench.send(0x080)
    bench.send(0x1A1, rtr=True, dlc=2)
    bench.run(5)
    assert [f for f in bench.take() if f.can_id in (0x181, 0x1A1) and not f.rx] == []


def test_tpdo_with_no_mapped_object_is_not_sent() -> None:
    """"Il campo dati di un PDO può essere compreso tra uno e otto byte": with NumOfEntries
    = 0 ("Per eliminare una mappatura bisogna agire con il NumOfEntries") there is no PDO to
    send — not on the event timer, not at a SYNC (types 0 and 1), not to a remote request —
    and a quiet span is not cut by its timer. Mapped again, it goes out as on entering
    Operational."""
    bench = make_bench()
    bench.ok(0x1800, 5, 20, 2)
    bench.nmt(NmtCommand.START)
    bench.run(50)
    bench.ok(0x1A00, 0, 0, 1)
    bench.take()
    bench.run(100)
    assert _tpdos(bench) == []
    node = bench.node
    assert node.quiet_until(1_000) > node.now_us + 1_000_000  # no timer left to keep
    for trans_type in (1, 0):
        bench.ok(0x1800, 2, trans_type, 1)
        for _ in range(3):
            bench.send(0x080)
            bench.run(2)
    bench.send(0x181, rtr=True, dlc=0)
    bench.run(2)
    assert _tpdos(bench) == []
    bench.ok(0x1800, 2, 255, 1)
    bench.ok(0x1A00, 0, 1, 1)
    bench.run(50)
    assert [hexs(f.data) for f in _tpdos(bench)][:2] == ["40 86", "40 86"]


def _tpdos_in(frames: list, can_id: int) -> list:
    return [f for f in frames if f.can_id == can_id]


def test_rpdo_shorter_than_its_mapping_is_not_processed() -> None:
    """DS 301: EMCY 0x8210, "PDO not processed due to length error"."""
    bench = _started()
    bench.send(0x201, bytes((0x06, 0x00)))  # 2 bytes, mapping needs 6
    bench.run(3)
    assert bench.drive.cw == 0
    assert [hexs(f.data) for f in bench.take() if f.can_id == 0x081] == \
        ["10 82 11 00 00 00 00 00"]


def test_rpdo_with_no_mapped_object_takes_nothing() -> None:
    """"Il campo dati di un PDO può essere compreso tra uno e otto byte"; "Per eliminare una
    mappatura bisogna agire con il NumOfEntries": an RPDO with 0x1600:0 = 0 is not in use, as
    its TPDO twin is not sent. A frame on its COB-ID, of any length, is not the node's: no
    write, no EMCY 0x8210 (nothing to be short of), not kept for the Sync, and the bus
    monitor does not name it RPDO1. Mapped again, the RPDO takes its frames as before."""
    bench = _started()
    bench.nmt(NmtCommand.ENTER_PRE_OPERATIONAL)
    bench.ok(0x1400, 2, 1, 1)  # synchronous: nothing may wait for the Sync either
    bench.ok(0x1600, 0, 0, 1)
    bench.nmt(NmtCommand.START)
    bench.run(3)
    bench.take()
    for data in (struct.pack("<Hi", 0x0006, 0), b"", bytes((0x06,))):
        bench.send(0x201, data)
        bench.run(2)
    recent = bench.node.monitor.recent(8)
    taken = [f["text"] for f in recent if f["id"] == "0x201"]
    assert len(taken) == 3 and not any(t.startswith("RPDO1") for t in taken), taken
    bench.ok(0x1600, 0, 2, 1)
    bench.send(0x080)
    bench.run(3)
    assert bench.drive.cw == 0
    assert [f for f in bench.take() if f.can_id == 0x081] == []
    bench.send(0x201, struct.pack("<Hi", 0x0006, 0))
    bench.send(0x080)
    bench.run(3)
    assert bench.drive.cw == 0x0006
    assert any(f["text"].startswith("RPDO1 0x6040") for f in bench.node.monitor.recent(8))


@pytest.mark.parametrize("node_id", [1, 2])
def test_seed_interpolator_example_sync_and_rpdo_loop(node_id: int) -> None:
    """Ch. 4 "Modo interpolatore": 60C2.1 = 1 ms, mode 7, RPDO1 = set-point + controlword
    synchronous, TPDO1 = position + statusword on every Sync, NMT start, enable, 0x001F,
    then every cycle a Sync and PDO 1 (set-point, controlword). Node 2 follows the "Nota":
    "1400, sub 1 = 513" first, so it takes node 1's RPDO1 (0x201)."""
    bench = make_bench(node_id=node_id)
    if node_id != 1:
        bench.ok(0x1400, 1, 513, 4)
    for index, sub, value, size in (
            (0x6092, 1, 6000, 4), (0x60C2, 1, 1, 1), (0x6060, 0, 7, 1),
            (0x1400, 2, 1, 1), (0x1600, 0, 0, 1), (0x1600, 1, 0x60C10120, 4),
            (0x1600, 2, 0x60400010, 4), (0x1600, 0, 2, 1),
            (0x1800, 2, 1, 1), (0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640020, 4),
            (0x1A00, 2, 0x60410010, 4), (0x1A00, 0, 2, 1)):
        bench.ok(index, sub, value, size)
    bench.nmt(NmtCommand.START)
    for cw in CANOPEN_ENABLE:
        bench.ok(0x6040, 0, cw, 2)
    start = bench.read(0x6064)
    bench.ok(0x60C1, 1, start, 4)  # the set-point where the axis stands, before 0x1F
    bench.ok(0x6040, 0, 0x001F, 2)
    bench.take()
    set_point = start
    for _ in range(600):
        bench.send(0x080)
        set_point += 10
        bench.send(0x201, struct.pack("<iH", set_point, 0x001F))
        bench.run(1)
    bench.run(20)
    feedback = [struct.unpack("<iH", f.data) for f in bench.take()
                if f.can_id == 0x180 + node_id]
    assert len(feedback) >= 595  # one TPDO per Sync
    positions = [p for p, _ in feedback]
    assert positions == sorted(positions)
    assert positions[-1] - start > 5_000  # the TPDO shows the position sampled at the Sync
    # the last RPDO waits for a Sync that never comes: the axis holds the one before
    assert abs(bench.read(0x6064) - (set_point - 10)) <= 2
    assert feedback[-1][1] & 0x106F == 0x1027  # operation enabled, bit 12: ip active



def test_seed_complete_example_interpolator_starts_where_homing_left_the_axis() -> None:
    """Ch. 4 "Esempio completo di asse gestito con interpolatore": homing (method 34, offset
    -1000: the axis then reads 1000), 0x000F, mode 7 ("L'asse rimane fermo in coppia fino
    all'attivazione dell'interpolatore"), 0x001F, then the loop "write Sync; write PDO 1,
    set-point, ControlWord" with no set-point written before it. The set-point "viene
    acquisito dal drive a seguito del Sync successivo": until one is, the axis holds where it
    stands, it does not run to a set-point nobody sent since (0x60C1:1's power-on 0)."""
    bench = make_bench()
    for index, sub, value, size in (
            (0x6092, 1, 6000, 4), (0x60C2, 1, 1, 1), (0x6098, 0, 34, 1),
            (0x607C, 0, -1000, 4), (0x6099, 2, 1000, 4),
            (0x1400, 2, 1, 1), (0x1600, 0, 0, 1), (0x1600, 1, 0x60C10120, 4),
            (0x1600, 2, 0x60400010, 4), (0x1600, 0, 2, 1)):
        bench.ok(index, sub, value, size)
    bench.nmt(NmtCommand.START)

    def cycles(ms: int, set_point: int | None = None) -> list[int]:
        positions = []
        for _ in range(ms):
            bench.send(0x080)  # "write Sync"
            if set_point is not None:  # "write PDO 1, set-point, ControlWord"
                bench.send(0x201, struct.pack("<iH", set_point, 0x001F))
            bench.run(1)
            positions.append(bench.drive.position_user)
        return positions

    for cw in CANOPEN_ENABLE:
        bench.ok(0x6040, 0, cw, 2)
    bench.ok(0x6060, 0, 6, 1)
    bench.ok(0x6040, 0, 0x001F, 2)
    for _ in range(200):
        cycles(50)
        if bench.drive.od.read(0x6041, 0) & 0x3000:
            break
    assert bench.drive.od.read(0x6041, 0) & 0x3000 == 0x1000  # homing attained
    bench.ok(0x6040, 0, 0x000F, 2)
    bench.ok(0x6060, 0, 7, 1)
    cycles(20)
    home = bench.drive.position_user
    assert abs(home - 1000) <= 2
    bench.ok(0x6040, 0, 0x001F, 2)  # "Attivazione interpolatore"
    held = cycles(20)  # Syncs, no PDO yet
    assert max(abs(p - home) for p in held) <= 2, (home, min(held), max(held))
    moving = cycles(300, set_point=home + 600)
    assert abs(moving[-1] - (home + 600)) <= 2
    assert bench.drive.alarms.latched == []


def test_remote_request_for_a_tpdo() -> None:
    """A remote frame on TPDO1's COB-ID (bit 30 clear) gets the current data in Operational
    (type 255, asynchronous: nothing recorded at a SYNC)."""
    bench = _started()
    bench.send(0x181, rtr=True, dlc=2)
    bench.run(2)
    assert [hexs(f.data) for f in bench.take() if f.can_id == 0x181] == ["40 86"]
    bench.ok(0x1800, 1, 0x4000_0181, 4)  # RTR not allowed (the PDO starts over: one event)
    bench.run(5)
    bench.take()
    bench.send(0x181, rtr=True, dlc=2)
    bench.run(2)
    assert [f for f in bench.take() if f.can_id == 0x181] == []
