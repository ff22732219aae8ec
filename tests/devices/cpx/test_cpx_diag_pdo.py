"""«New Message Available» in the process data (seed 002 §2.5.2 l. 539-541; Tab. 27 l. 674-675
0x1A40 "Diag History – TxPDO"): an optional TxPDO a master assigns through 0x1C13 in PREOP
(ETG.1000.6 / CiA 301: sub 0 = 0, the entries, sub 0 = n); devices/cpx/assignment.py."""

from __future__ import annotations

import pytest
from cpx_bench import STI, TAB9_MODULES, Bench

from devices.cpx.assignment import DIAG_PDO, TX_ASSIGN
from devices.ethercat import AlState
from devices.od import AbortCode, Access, SdoAbort

MODULE_TX = [0x1A00, 0x1A04, 0x1A01]  # Tab. 9 with STI: bus module, 4AI, 16DI


def _read(bench: Bench) -> list[int]:
    cpx = bench.cpx
    return [cpx.cmd_read_object(TX_ASSIGN, s)
            for s in range(1, cpx.cmd_read_object(TX_ASSIGN, 0) + 1)]


def assign(bench: Bench, pdos: list[int]) -> None:
    cpx = bench.cpx
    cpx.cmd_write_object(TX_ASSIGN, 0, 0)
    for sub, pdo in enumerate(pdos, start=1):
        cpx.cmd_write_object(TX_ASSIGN, sub, pdo)
    cpx.cmd_write_object(TX_ASSIGN, 0, len(pdos))


@pytest.fixture
def bench() -> Bench:
    bench = Bench(TAB9_MODULES, master=False, **STI)
    bench.cpx.request_state(AlState.PREOP)
    return bench


def test_default_assignment_is_the_modules_only(bench: Bench) -> None:
    assert _read(bench) == MODULE_TX
    assert DIAG_PDO not in _read(bench)


def test_master_assigns_0x1a40_in_preop(bench: Bench) -> None:
    assign(bench, [*MODULE_TX, DIAG_PDO])
    assert _read(bench) == [*MODULE_TX, DIAG_PDO]
    bench.apply("restart")  # RAM: a start brings the default back
    assert _read(bench) == MODULE_TX


@pytest.mark.parametrize(("sub", "value", "code"), [
    (1, 0x1A41, AbortCode.VALUE_RANGE),  # no such TxPDO
    (1, 0x1601, AbortCode.VALUE_RANGE),  # an RxPDO
])
def test_unknown_pdo_refused(bench: Bench, sub: int, value: int, code: AbortCode) -> None:
    bench.cpx.cmd_write_object(TX_ASSIGN, 0, 0)
    with pytest.raises(SdoAbort) as exc:
        bench.cpx.cmd_write_object(TX_ASSIGN, sub, value)
    assert exc.value.code == code


def test_entry_while_sub0_not_zero_and_outside_preop_refused(bench: Bench) -> None:
    with pytest.raises(SdoAbort) as exc:
        bench.cpx.cmd_write_object(TX_ASSIGN, 4, DIAG_PDO)
    assert exc.value.code == AbortCode.UNSUPPORTED_ACCESS
    bench.cpx.request_state(AlState.INIT)
    with pytest.raises(SdoAbort) as exc:
        bench.cpx.cmd_write_object(TX_ASSIGN, 0, 0)
    assert exc.value.code == AbortCode.CANNOT_STORE_STATE
    assert _read(bench) == MODULE_TX


@pytest.mark.parametrize("pdos", [
    [DIAG_PDO, *MODULE_TX],  # first: every module's data one bit later
    [*MODULE_TX[:2], DIAG_PDO, MODULE_TX[2]],  # the 16DI off its byte
])
def test_0x1a40_only_after_the_module_data(bench: Bench, pdos: list[int]) -> None:
    """Tab. 27: 0x1A40 maps one bit (sub 0 = 1, RO: no padding entry); §2.3.1 / Tab. 9 give
    every module's data its byte address. Anywhere but last the bit would move the module
    data after it off those addresses, so sub 0 = n refuses it (0x06090030) and 0x1C13 stays
    empty until a valid n (docs/cpx-e-ec.md choice 36)."""
    cpx = bench.cpx
    cpx.cmd_write_object(TX_ASSIGN, 0, 0)
    for sub, pdo in enumerate(pdos, start=1):
        cpx.cmd_write_object(TX_ASSIGN, sub, pdo)
    with pytest.raises(SdoAbort) as exc:
        cpx.cmd_write_object(TX_ASSIGN, 0, len(pdos))
    assert (exc.value.code, exc.value.sub) == (AbortCode.VALUE_RANGE, 0)
    assert cpx.cmd_read_object(TX_ASSIGN, 0) == 0
    assign(bench, [*MODULE_TX, DIAG_PDO])  # last: accepted
    assert _read(bench) == [*MODULE_TX, DIAG_PDO]


@pytest.mark.parametrize("pdos", [
    [MODULE_TX[1], MODULE_TX[0], MODULE_TX[2]],  # reordered: the 4AI's data before I0
    [MODULE_TX[0], MODULE_TX[2], MODULE_TX[1]],  # the 16DI before the 4AI: off I72 ... I87
    MODULE_TX[:2],  # the 16DI left out
    [MODULE_TX[0], MODULE_TX[2], DIAG_PDO],  # the 4AI left out, 0x1A40 last
    [MODULE_TX[1], MODULE_TX[0], MODULE_TX[2], DIAG_PDO],  # reordered, 0x1A40 last
])
def test_module_txpdos_only_as_the_addressing_rules_place_them(
        bench: Bench, pdos: list[int]) -> None:
    """§2.3.1: the bus module assigns the addresses itself — the bus module's diagnosis,
    analog, then digital modules, each by module number — and Tab. 9 is the image a PLC
    programmer reads addresses from. A 0x1C13 that reorders or leaves out module TxPDOs
    would move module data off those addresses: sub 0 = n refuses it (0x06090030), as it
    refuses 0x1A40 before a module (docs/cpx-e-ec.md choice 37)."""
    cpx = bench.cpx
    cpx.cmd_write_object(TX_ASSIGN, 0, 0)
    for sub, pdo in enumerate(pdos, start=1):
        cpx.cmd_write_object(TX_ASSIGN, sub, pdo)
    with pytest.raises(SdoAbort) as exc:
        cpx.cmd_write_object(TX_ASSIGN, 0, len(pdos))
    assert (exc.value.code, exc.value.sub) == (AbortCode.VALUE_RANGE, 0)
    assert cpx.cmd_read_object(TX_ASSIGN, 0) == 0


def test_safeop_refused_while_0x1c13_is_left_empty(bench: Bench) -> None:
    """Sub 0 = 0 is the first step of a change (CiA 301), not an assignment: PREOP -> SAFEOP
    with the modules' inputs unassigned is refused with 0x0024 Invalid Input Mapping."""
    cpx = bench.cpx
    cpx.cmd_write_object(TX_ASSIGN, 0, 0)
    cpx.request_state(AlState.SAFEOP)
    assert cpx.al_state is AlState.PREOP and cpx.al_status_code == 0x0024
    cpx.cmd_write_object(TX_ASSIGN, 0, len(MODULE_TX))  # the entries are still there
    cpx.request_state(AlState.SAFEOP, ack=True)  # AL control bit 4 (ETG.1000.6)
    assert cpx.al_state is AlState.SAFEOP and cpx.al_status_code == 0


def test_an_empty_default_is_an_assignment() -> None:
    """Without modules with inputs and without diagnosis (DIL off / off) the default 0x1C13 is
    empty: sub 0 = 0 is then the module's own assignment and SAFEOP is reached."""
    bench = Bench(["CPX-E-8DO"], master=False)
    cpx = bench.cpx
    cpx.request_state(AlState.PREOP)
    assert cpx.cmd_read_object(TX_ASSIGN, 0) == 0
    cpx.request_state(AlState.SAFEOP)
    assert cpx.al_state is AlState.SAFEOP


@pytest.mark.parametrize("sub", [0, 1, 4])
def test_0x1c13_says_it_is_written_in_preop_only(bench: Bench, sub: int) -> None:
    """What the entry description tells a master (SDO Information, the Objects tab) is what
    0x1C13 does: a write outside PREOP aborts 0x08000022 (above), so its access is "read
    always, write in PREOP" (r-wps, ETG.1000.6 access word 0x000F), as the drive's and the
    TRS-CAT's; it used to say plain rw (0x003F, writable in SAFEOP and OP too)."""
    assert bench.cpx.od is not None
    assert bench.cpx.od.entry(TX_ASSIGN, sub).access is Access.RW_PREOP
