"""0xF030 Configured Module Ident List and coupler alarm 0x14 (seed 000 §7.5 row 0x14, §7.7
0x0070; ETG.5001 MDP, the device type 5001 of §6.1). Choices: docs/fastcat-coupler.md."""

from __future__ import annotations

import struct

import pytest
from fastcat_bench import Bench

from devices.ethercat import AlState
from devices.fastcat.alarms import COUPLER, Alarm
from devices.master import EtherCatMaster
from devices.master.network import InitCmd, SlaveDescription
from devices.od import AbortCode, Access, SdoAbort

DB16, AI8D, AI8C = 0xFA01, 0xFA05, 0xFA06  # 0xF050.1..3 of the bench's rail (catalog.py)


def preop() -> Bench:
    bench = Bench()
    bench.settle()
    bench.fc.request_state(AlState.PREOP)
    assert bench.fc.al_state is AlState.PREOP
    return bench


def configure(bench: Bench, idents: list[int], count: int | None = None) -> None:
    """What a master's start-up list does: sub 0 = 0, the entries, then sub 0 = the count."""
    bench.fc.mailbox_write(0xF030, 0, 0)
    for sub, ident in enumerate(idents, start=1):
        bench.fc.mailbox_write(0xF030, sub, ident)
    bench.fc.mailbox_write(0xF030, 0, len(idents) if count is None else count)


def to_safeop(bench: Bench) -> None:
    bench.fc.request_state(AlState.SAFEOP)
    bench.step()


def test_f030_exists_and_defaults_to_not_configured() -> None:
    bench = preop()
    assert [bench.read(0xF030, sub) for sub in range(17)] == [0] * 17
    bench.fc.mailbox_write(0xF030, 1, DB16)  # a master's start-up write
    assert bench.read(0xF030, 1) == DB16
    raw = bench.fc.sdo_upload(0xF030, 1)
    assert raw == struct.pack("<I", DB16)
    with pytest.raises(SdoAbort) as info:
        bench.fc.mailbox_write(0xF030, 0, 17)  # 16 modules at most (§2)
    assert info.value.code is AbortCode.VALUE_TOO_HIGH


@pytest.mark.parametrize("state", [AlState.INIT, AlState.SAFEOP, AlState.OP])
def test_f030_is_written_in_preop_only(state: AlState) -> None:
    """ETG.5001: the master writes the configured list in PRE-OP (its PS start-up list)."""
    bench = Bench()
    bench.to_state(state) if state is not AlState.INIT else bench.settle()
    with pytest.raises(SdoAbort) as info:
        bench.fc.od.write(0xF030, 1, DB16)
    assert info.value.code is AbortCode.CANNOT_STORE_STATE
    assert bench.read(0xF030, 1) == 0


def test_f030_says_it_is_written_in_preop_only() -> None:
    """What the entries say of their access matches what a write gets: "r-wps" (read always,
    written in PRE-OP only, Access.RW_PREOP) in the Objects tab and the SDO information's
    access word (write in PRE-OP only), as the TRS-CAT's 0xF030. Plain "rw" told a
    configurator it could write the list in SAFEOP / OP, where the coupler aborts 0x08000022."""
    from app.ethercat_wire.coe import READ_ALL, WRITE_PREOP, access_word
    from app.ui.panels.object_dictionary import read_rows

    bench = preop()
    entries = [bench.fc.od.entry(0xF030, sub) for sub in range(17)]
    assert {e.access for e in entries} == {Access.RW_PREOP}
    assert {access_word(e) for e in entries} == {READ_ALL | WRITE_PREOP}
    assert {r.access for r in read_rows(bench.fc) if r.index == 0xF030} == {"r-wps"}


def test_matching_list_lets_the_coupler_reach_safeop() -> None:
    bench = preop()
    configure(bench, [DB16, AI8D, AI8C])
    to_safeop(bench)
    assert bench.fc.al_state is AlState.SAFEOP and bench.fc.alarm is None


def test_mismatch_refuses_safeop_with_0x0070_and_raises_0x14() -> None:
    """§7.5 0x14 SLOT_NOT_MATCHING, byte 0 = the slot n; §7.7 0x0070."""
    bench = preop()
    mark = bench.mark()
    configure(bench, [DB16, AI8C, AI8C])  # slot 2 holds an AI8D
    to_safeop(bench)
    assert bench.fc.al_state is AlState.PREOP
    assert bench.fc.al_status & 0x10 and bench.fc.al_status_code == 0x0070
    assert bench.fc.alarm == Alarm(COUPLER, 0x14, 2)
    assert bench.emergencies(mark) == ["02 00 00 14 00"]
    assert bench.read(0x5400, 0) == 0x1400_0002


def test_behind_a_module_alarm_0x14_waits_but_safeop_is_still_refused_with_0x0070() -> None:
    """A module alarm latched first: 0x14 is a coupler cause behind it and waits (no
    emergency, 0x5400 the module alarm's, §7 "il primo allarme"), but the SAFEOP request is
    refused with 0x0070 all the same: ETG.5001's answer to a rail the master did not
    configure, whose process image is not the one it expects (docs "0xF030")."""
    bench = preop()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.step()
    mark = bench.mark()
    configure(bench, [DB16, AI8C, AI8C])  # slot 2 holds an AI8D
    to_safeop(bench)
    assert bench.fc.al_state is AlState.PREOP
    assert (bench.fc.al_status, bench.fc.al_status_code) == (0x12, 0x0070)
    assert bench.emergencies(mark) == [] and bench.read(0x5400, 0) == 0x000B_0002
    assert bench.fc.snapshot()["leds"]["ERR"] == "blinking"


@pytest.mark.parametrize(("idents", "count", "slot"), [
    ([DB16, 0, AI8C], None, None),  # 0: the master leaves slot 2 unchecked
    ([0, 0, 0], None, None),
    ([AI8C, AI8D, DB16], 0, None),  # sub 0 = 0: no list, no check
    ([DB16, AI8D], None, 3),  # a detected module the master did not configure
    ([DB16, AI8D, AI8C, 0], None, None),  # a 0 beyond the rail checks nothing
    ([DB16, AI8D, AI8C, DB16], None, 4),  # a configured module that is not there
    ([DB16, AI8D, AI8C, DB16], 3, None),  # only subs 1..sub 0 are the list
])
def test_which_slot_mismatches(idents: list[int], count: int | None, slot: int | None) -> None:
    bench = preop()
    configure(bench, idents, count)
    to_safeop(bench)
    if slot is None:
        assert bench.fc.al_state is AlState.SAFEOP and bench.fc.alarm is None
    else:
        assert bench.fc.al_state is AlState.PREOP
        assert bench.fc.alarm == Alarm(COUPLER, 0x14, slot)


def test_reset_fault_clears_0x14_once_the_list_is_right() -> None:
    """0x14 <= 0x7F: a Reset fault edge clears it (§6.17, §7), only without its cause."""
    bench = preop()
    configure(bench, [DB16, AI8C, AI8C])
    to_safeop(bench)
    bench.reset_fault()
    bench.step()
    assert bench.fc.alarm == Alarm(COUPLER, 0x14, 2)  # the list still disagrees
    bench.fc.mailbox_write(0xF030, 2, AI8D)
    bench.reset_fault()
    bench.step()
    assert bench.fc.alarm is None
    bench.fc.request_state(AlState.SAFEOP, ack=True)  # AL control bit 4 (ETG.1000.6)
    assert bench.fc.al_state is AlState.SAFEOP


def test_a_correct_list_after_the_refusal_does_not_raise_again() -> None:
    """The list is checked at the PREOP -> SAFEOP request, not while the master writes it."""
    bench = preop()
    configure(bench, [DB16, AI8C, AI8C])
    bench.run(0.5)
    assert bench.fc.alarm is None  # written but not yet checked
    to_safeop(bench)
    assert bench.fc.alarm == Alarm(COUPLER, 0x14, 2)


@pytest.mark.parametrize("rescan", ["init", "cnf"])
def test_the_list_does_not_survive_a_scan(rescan: str) -> None:
    """Volatile, never in flash: every scan (return to INIT, CNF) rebuilds the dictionary
    and the master writes its list again at its next start-up; the resync clears 0x14."""
    bench = preop()
    configure(bench, [DB16, AI8C, AI8C])
    to_safeop(bench)
    assert bench.fc.alarm is not None
    if rescan == "init":
        bench.fc.request_state(AlState.INIT)
    else:
        bench.apply("hold_cnf", seconds=3.0)
    bench.run(3.0)
    bench.run_until(lambda: bench.fc.scan is None)
    assert bench.fc.alarm is None
    bench.fc.request_state(AlState.PREOP)
    assert [bench.read(0xF030, sub) for sub in range(4)] == [0, 0, 0, 0]
    to_safeop(bench)
    assert bench.fc.al_state is AlState.SAFEOP
    assert bench.flash.writes == (1 if rescan == "cnf" else 0)  # only CNF stores (§2)


def test_master_start_up_list_refused_like_twincat() -> None:
    """A network description with the FastCAT's 0xF030 in PS (TwinCAT's start-up list): the
    coupler stays in PREOP with 0x0070 and latches 0x14 on the first wrong slot."""
    bench = Bench()
    wrong = [DB16, AI8D, DB16]
    cmds = (InitCmd("PS", 0xF030, 0, b"\x00"),
            *(InitCmd("PS", 0xF030, s, struct.pack("<I", v)) for s, v in enumerate(wrong, 1)),
            InitCmd("PS", 0xF030, 0, b"\x03"))
    desc = SlaveDescription(0, "Box 1 (FastCAT)", "fastcat", None, None, None, 1001, False,
                            cmds)
    bench.master = EtherCatMaster("master", slaves=[bench.fc], descriptions=[desc])
    bench.run(12.0)
    assert bench.fc.al_state is AlState.PREOP and bench.fc.al_status_code == 0x0070
    assert bench.fc.alarm == Alarm(COUPLER, 0x14, 3)
