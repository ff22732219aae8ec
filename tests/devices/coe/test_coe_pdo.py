"""PDO contents, assignment rules and the process image (seed 004 ch. 5 "PDO", "Utilizzo degli
Slots", "Mappatura dinamica PDO"; mapping rules of ch. 4 "Servizio SDO", which ch. 5 refers to;
the TwinCAT "Process Data" screen of ch. 5 for the image layout).
"""

from __future__ import annotations

import struct

import pytest
from coe_bench import CIA402_ENABLE, make_bench

from devices.coe import process_image
from devices.coe.assignment import SLOTS
from devices.device import CommandError
from devices.ethercat import AlState

PREOP, SAFEOP, OP = AlState.PREOP, AlState.SAFEOP, AlState.OP

# Ch. 5 "PDO": the eight PDOs as printed (0x6060 / 0x6061 printed "2 bytes": they are 8-bit
# objects, mapped with their own length, docs/ethercat-coe.md §PDO contents).
DEFAULT_CONTENTS = {
    0x1600: [0x60400010, 0x60C10120],
    0x1601: [0x60400010, 0x60600008],
    0x1602: [0x60400010, 0x607A0020],
    0x1603: [0x60400010, 0x60FF0020],
    0x1A00: [0x60410010],
    0x1A01: [0x60410010, 0x60610008],
    0x1A02: [0x60410010, 0x60640020],
    0x1A03: [0x60410010, 0x606C0020],
}


@pytest.mark.parametrize(("index", "entries"), DEFAULT_CONTENTS.items())
def test_default_pdo_contents(index: int, entries: list[int]) -> None:
    bench = make_bench()
    bench.go(PREOP)
    assert bench.read(index, 0) == len(entries)
    assert [bench.read(index, sub) for sub in range(1, len(entries) + 1)] == entries


def test_default_assignment_is_the_interpolated_slot() -> None:
    """Ch. 5 "Nota importante: come default ... sono selezionati gli oggetti 0x1600 e 0x1A02
    per l'interpolazione in posizione"."""
    bench = make_bench()
    bench.go(PREOP)
    assert (bench.read(0x1C12, 0), bench.read(0x1C12, 1)) == (1, 0x1600)
    assert (bench.read(0x1C13, 0), bench.read(0x1C13, 1)) == (1, 0x1A02)
    assert [bench.read(0x1C00, s) for s in range(5)] == [4, 1, 2, 3, 4]


OK = "ok"


@pytest.mark.parametrize(("writes", "result"), [
    ([(0x1C12, 0, 0, 1), (0x1C12, 1, 0x1603, 2), (0x1C12, 0, 1, 1)], OK),
    ([(0x1C12, 1, 0x1603, 2)], "0x06010000"),  # sub 0 must be 0 first
    ([(0x1C12, 0, 0, 1), (0x1C12, 1, 0x1A00, 2)], "0x06090030"),  # a TxPDO in 0x1C12
    ([(0x1C13, 0, 0, 1), (0x1C13, 1, 0x1604, 2)], "0x06090030"),  # no such PDO
    ([(0x1C13, 0, 0, 1), (0x1C13, 1, 0x1A04, 2)], "0x06090030"),
    ([(0x1C12, 0, 0, 1), (0x1C12, 0, 5, 1)], "0x06090031"),  # four PDOs per direction
    ([(0x1C12, 0, 0, 1), (0x1C12, 1, 0, 2), (0x1C12, 0, 1, 1)], "0x06090030"),  # sub 1 empty
    ([(0x1C13, 0, 0, 1), (0x1C13, 1, 0x1A02, 2), (0x1C13, 2, 0x1A02, 2), (0x1C13, 0, 2, 1)],
     "0x06090030"),  # the same PDO twice
    ([(0x1C12, 5, 0x1600, 2)], "0x06090011"),
    ([(0x1C12, 0, 0, 1), (0x1C12, 1, 0x1600, 4)], "0x06070012"),  # 4 bytes to a 16-bit object
    # mapping objects (ch. 4 rules): remove with sub 0, at most 8 bytes, byte granularity
    ([(0x1A00, 1, 0x60640020, 4)], "0x06010000"),
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640020, 4), (0x1A00, 2, 0x60410010, 4),
      (0x1A00, 0, 2, 1)], OK),
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640020, 4), (0x1A00, 2, 0x606C0020, 4),
      (0x1A00, 3, 0x60410010, 4), (0x1A00, 0, 3, 1)], "0x06040042"),  # 10 bytes
    ([(0x1600, 0, 0, 1), (0x1600, 1, 0x60410010, 4)], "0x06040041"),  # read-only in an RxPDO
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60640010, 4)], "0x06040041"),  # wrong length
    ([(0x1A00, 0, 0, 1), (0x1A00, 1, 0x60920120, 4)], "0x06040041"),  # feed: not mappable
])
def test_assignment_and_mapping_rules(writes: list[tuple[int, int, int, int]],
                                      result: str) -> None:
    bench = make_bench()
    bench.go(PREOP)
    outcome = OK
    for index, sub, value, size in writes:
        outcome = bench.abort(lambda i=index, s=sub, v=value, n=size: bench.write(i, s, v, n))
        if outcome != OK:
            break
    assert outcome == result


@pytest.mark.parametrize("state", [SAFEOP, OP])
@pytest.mark.parametrize("index", [0x1C12, 0x1C13, 0x1600, 0x1A03])
def test_mapping_and_assignment_are_written_in_preop_only(state: AlState, index: int) -> None:
    """Ch. 5 "P -> S: Il Master configura i parametri dello slave via mailbox ... la mappatura
    dei process data": later the objects refuse with 0x08000022 (and stay readable)."""
    bench = make_bench()
    bench.up_to(state)
    assert bench.abort(lambda: bench.write(index, 0, 0, 1)) == "0x08000022"
    assert bench.read(index, 0) >= 1


@pytest.mark.parametrize(("index", "sub"), [
    (0x1C12, 0), (0x1C12, 4), (0x1C13, 1), (0x1600, 0), (0x1603, 8), (0x1A00, 1), (0x1A03, 0)])
def test_sdo_information_says_mapping_and_assignment_are_written_in_preop_only(
        index: int, sub: int) -> None:
    """What SDO Information (ch. 5 "SDO Info support ... visualizzare l'elenco aggiornato degli
    oggetti") describes is what the drive does: these objects refuse a write in SAFEOP / OP
    (0x08000022, above), so their access is "read always, write in PREOP" (r-wps, ETG.1000.6
    access word 0x000F), as the TRS-CAT's 0xF030; they used to say plain rw (0x003F)."""
    bench = make_bench()
    bench.up_to(PREOP)
    assert bench.slave.sdo_info(index, sub)["access"] == "r-wps"


def test_remapping_first_the_pdo_then_the_assignment() -> None:
    """Ch. 5: "agendo prima direttamente sugli oggetti 0x1600 - 0x1603 o 0x1A00 - 0x1A03. Ed in
    seguito su gli oggetti 0x1C12 e 0x1C13"."""
    bench = make_bench()
    bench.go(PREOP)
    for index, sub, value, size in ((0x1A00, 0, 0, 1), (0x1A00, 1, 0x60410010, 4),
                                    (0x1A00, 2, 0x60640020, 4), (0x1A00, 3, 0x60610008, 4),
                                    (0x1A00, 0, 3, 1), (0x1C13, 0, 0, 1),
                                    (0x1C13, 1, 0x1A00, 2), (0x1C13, 0, 1, 1)):
        bench.write(index, sub, value, size)
    bench.go(SAFEOP)
    bench.run(1)
    assert bench.inputs("<Hib") == (bench.drive.statusword, bench.drive.position_user,
                                    bench.drive.mode)


@pytest.mark.parametrize(("assign", "code"), [
    # "una qualunque configurazione possibile fra i pdo di default" (ch. 5): the controlword
    # that every default RxPDO carries may come twice; the last one in the image wins
    ((0x1C12, [0x1600, 0x1602]), None),
    ((0x1C12, [0x1600, 0x1601]), None),  # "ulteriormente mappare gli oggetti 0x1601"
    ((0x1C12, [0x1603, 0x1601]), None),
    ((0x1C12, [0x1600, 0x1601, 0x1602, 0x1603]), None),
    ((0x1C12, [0x1601]), None),
    ((0x1C12, []), None),  # no outputs at all is a valid configuration
    ((0x1C13, [0x1A00, 0x1A02, 0x1A03]), None),  # inputs may repeat the statusword
])
def test_assignment_checked_at_preop_to_safeop(assign: tuple[int, list[int]],
                                               code: int | None) -> None:
    bench = make_bench()
    bench.go(PREOP)
    index, pdos = assign
    bench.write(index, 0, 0, 1)
    for sub, pdo in enumerate(pdos, start=1):
        bench.write(index, sub, pdo, 2)
    bench.write(index, 0, len(pdos), 1)
    bench.go(SAFEOP)
    if code is None:
        assert bench.slave.al_state is SAFEOP
    else:
        assert (bench.slave.al_state, bench.slave.al_status_code) == (PREOP, code)


def test_an_empty_pdo_in_the_assignment_refuses_safeop_with_alarm_33() -> None:
    """Ch. 5 alarm table: 33 "Errore mappatura pdo non eseguita correttamente" = 0x6320; the
    alarm stays until a valid mapping passes and a reset (0x80 on 0x6040) clears it."""
    bench = make_bench()
    bench.go(PREOP)
    bench.write(0x1A02, 0, 0, 1)  # 0x1A02 is assigned and now maps nothing
    bench.go(SAFEOP)
    assert (bench.slave.al_state, bench.slave.al_status_code) == (PREOP, 0x0024)
    assert bench.drive.alarms.latched == [33]
    assert bench.read(0x603F) == 0x6320
    assert bench.emergencies[0][:2] == b"\x20\x63"
    bench.cw(0x0080, 0x0000)
    assert bench.drive.alarms.latched == [33]  # "la condizione di allarme persiste"
    bench.write(0x1A02, 0, 2, 1)
    bench.go(SAFEOP)
    assert bench.slave.al_state is SAFEOP
    bench.cw(0x0080, 0x0000)
    assert bench.drive.alarms.latched == []


def _slot_bench(slot: str):
    bench = make_bench()
    bench.go(PREOP)
    bench.slave.apply("select_slot", {"slot": slot})
    bench.up_to(OP)
    return bench


@pytest.mark.parametrize("slot", SLOTS)
def test_slots_select_their_pdos_and_mode(slot: str) -> None:
    """Ch. 5 "Utilizzo degli Slots": Position 0x1602 / 0x1A02 mode 1, Interpolated 0x1600 /
    0x1A02 mode 7, Velocity 0x1603 / 0x1A03 mode 3; CSP = 8 on the Position PDOs."""
    bench = _slot_bench(slot)
    chosen = SLOTS[slot]
    assert (bench.read(0x1C12, 1), bench.read(0x1C13, 1)) == (chosen.rx, chosen.tx)
    assert bench.read(0x6061, signed=True) == chosen.mode
    assert bench.slave.slot() == slot


def test_position_slot_round_trip() -> None:
    bench = _slot_bench("position")
    for value in CIA402_ENABLE:
        bench.outputs("<Hi", value, 0, ms=2)
    bench.outputs("<Hi", 0x000F, 6000, ms=2)
    bench.outputs("<Hi", 0x001F, 6000)
    bench.run_until(lambda: bench.drive.position_user == 6000
                    and bench.drive.statusword & 0x0400, 10_000)
    status, position = bench.inputs("<Hi")
    assert position == 6000 and status == bench.drive.statusword


def test_ready_to_switch_on_in_mode_7_is_the_twincat_screens_0x0621() -> None:
    """Ch. 5 "Settaggi SM / DC" (l. 4636-4638): TwinCAT online, the Interpolated slot's drive
    in Ready to switch on reads "Status Word 0x0621" and "Mode of Operation 0x07 (7)"."""
    bench = _slot_bench("interpolated")
    start = bench.drive.position_user
    for value in (0x0000, 0x0006):
        bench.outputs("<Hi", value, start, ms=2)
    assert bench.inputs("<Hi")[0] == 0x0621 == bench.read(0x6041)
    assert bench.read(0x6061, signed=True) == 7


def test_velocity_slot_round_trip() -> None:
    bench = _slot_bench("velocity")
    for value in CIA402_ENABLE:
        bench.outputs("<Hi", value, 0, ms=2)
    bench.outputs("<Hi", 0x000F, 1000, ms=3000)
    status, velocity = bench.inputs("<Hi")
    assert velocity == 1000 == bench.drive.read_register(8)
    assert status & 0x0400  # target reached (velocity window)


@pytest.mark.parametrize("slot", ["interpolated", "csp"])
def test_interpolated_and_csp_follow_a_set_point_per_cycle(slot: str) -> None:
    """Interpolated: 0x60C1:1 + controlword bit 4; CSP: 0x607A every cycle, no start bit. The
    SM2 event is the drive's Sync (ch. 5 "Settaggi SM / DC": SM-Synchron)."""
    bench = _slot_bench(slot)
    start = bench.drive.position_user
    for value in CIA402_ENABLE:
        bench.outputs("<Hi", value, start, ms=2)
    run = 0x001F if slot == "interpolated" else 0x000F
    for k in range(1, 501):
        bench.outputs("<Hi", run, start + 6 * k)  # 6 units per 1 ms cycle = 60 rpm
    bench.run(20)
    status, position = bench.inputs("<Hi")
    assert position == start + 3000 == bench.drive.position_user
    assert status & 0x1000  # 0x6041 bit 12: interpolation active / following the command
    assert bench.read(0x6061, signed=True) == SLOTS[slot].mode
    assert bench.read(0x6040) == run  # reads back as the master wrote it


def test_csp_ends_when_another_mode_is_written() -> None:
    bench = _slot_bench("csp")
    assert bench.slave.csp.active
    bench.drive.apply("set_mode", {"mode": 1})
    assert bench.read(0x6061, signed=True) == 1 and not bench.slave.csp.active


def _assign(bench, index: int, pdos: list[int]) -> None:
    bench.write(index, 0, 0, 1)
    for sub, pdo in enumerate(pdos, start=1):
        bench.write(index, sub, pdo, 2)
    bench.write(index, 0, len(pdos), 1)


def test_modes_of_operation_through_process_data() -> None:
    """Ch. 5: "si possono ulteriormente mappare gli oggetti 0x1601 e 0x1A01 per controllare le
    modalità operative via pdo": 0x1601 / 0x1A01 alone ..."""
    bench = make_bench()
    bench.go(PREOP)
    _assign(bench, 0x1C12, [0x1601])
    _assign(bench, 0x1C13, [0x1A01])
    bench.up_to(OP)
    for mode in (3, 8, 6, 7):
        bench.outputs("<Hb", 0, mode, ms=2)
        assert bench.inputs("<Hb")[1] == mode


@pytest.mark.parametrize("slot", ["interpolated", "position", "velocity"])
def test_modes_of_operation_through_process_data_next_to_a_slot(slot: str) -> None:
    """... and "ulteriormente" (in addition) to a slot's PDOs, as the TwinCAT screen of ch. 5
    "Settaggi SM / DC" shows (Status Word twice, then Mode of Operation display): 0x1601 after
    the slot's RxPDO, 0x1A01 after its TxPDO. The controlword is in both RxPDOs; the image is
    applied in order and each object is written once per frame with its last value, so the
    drive sees the controlword of 0x1601 only (docs/ethercat-coe.md §PDO assignment)."""
    rx, tx = SLOTS[slot].rx, SLOTS[slot].tx
    bench = make_bench()
    bench.go(PREOP)
    _assign(bench, 0x1C12, [rx, 0x1601])
    _assign(bench, 0x1C13, [tx, 0x1A01])
    bench.go(SAFEOP)
    assert bench.slave.al_state is SAFEOP and bench.drive.alarms.latched == []
    assert process_image.size(bench.slave.rx_assigned) == 2 + 4 + 2 + 1
    bench.up_to(OP)
    mode = SLOTS[slot].mode
    for cw in CIA402_ENABLE:  # the first controlword stays 0: only the last one counts
        bench.outputs("<HiHb", 0x0000, 0, cw, mode, ms=2)
    assert bench.inputs("<HiHb")[3] == mode
    word = bench.inputs("<HiHb")[0]
    assert word == bench.inputs("<HiHb")[2] == bench.drive.statusword
    assert word & 0x6F == 0x27  # operation enabled, and it stays so frame after frame
    bench.run(20)
    assert bench.drive.statusword & 0x6F == 0x27


def test_a_repeated_output_object_is_written_once_with_its_last_value() -> None:
    writes = [(0x6040, 0, 0x0000), (0x60C1, 1, 5), (0x6040, 0, 0x000F), (0x6060, 0, 7)]
    assert process_image.last_writes(writes) == writes[1:]
    assert process_image.last_writes(writes[:2]) == writes[:2]


def test_image_layout_as_twincat_shows_it() -> None:
    """Ch. 5 TwinCAT "Process Data": 0x1A02 = 0x6041 at offset 0.0, 0x6064 at 2.0, size 6.0."""
    slave = make_bench().slave
    rows = process_image.layout(slave.tx_assigned)
    assert [(r.index, r.offset, r.bits) for r in rows] == [(0x6041, 0, 16), (0x6064, 2, 32)]
    assert process_image.size(slave.rx_assigned) == 6


def test_outputs_image_must_match_the_assignment() -> None:
    bench = make_bench()
    with pytest.raises(CommandError, match="6 bytes"):
        bench.slave.write_outputs(b"\x00\x00")
    with pytest.raises(CommandError, match="hex"):
        bench.slave.apply("set_outputs", {"data": "zz"})
    bench.slave.apply("set_outputs", {"data": "06 00 00 00 00 00"})
    assert bench.slave.outputs == struct.pack("<Hi", 6, 0)


def test_select_slot_outside_preop_is_refused() -> None:
    bench = make_bench()
    bench.up_to(SAFEOP)
    with pytest.raises(CommandError, match="PREOP"):
        bench.slave.apply("select_slot", {"slot": "velocity"})
