"""The object dictionary of Tab. 27 (seed 002 §3) and the ident check 0xF030 / 0xF050 at
PREOP -> SAFEOP (Tab. 17 Text-IDs 0x3800 / 0x3801)."""

from __future__ import annotations

from typing import Any

import pytest
from cpx_bench import TAB9_MODULES, Bench, tab9

from devices.cpx.catalog import BUS_STATUS_BITS, module_type
from devices.cpx.codes import TEXT_IDENT_FAILED, TEXT_IDENT_SKIPPED
from devices.cpx.objects import pdo_entry
from devices.ethercat import AlState
from devices.od import AbortCode, Access, DataType, SdoAbort

U8, U16, U32 = DataType.UNSIGNED8, DataType.UNSIGNED16, DataType.UNSIGNED32
BOOL, STR = DataType.BOOLEAN, DataType.VISIBLE_STRING
RO, RW = Access.RO, Access.RW
ANY = object()

# Tab. 27 for the §2.3.2 system with status bits: (index, sub, type, access, value).
TAB27: list[tuple[int, int, DataType, Access, Any]] = [
    (0x1000, 0, U32, RO, 0x0456_1389), (0x1001, 0, U8, RO, 0),
    (0x1008, 0, STR, RO, "CPX-E-EC"), (0x1009, 0, STR, RO, ANY), (0x100A, 0, STR, RO, ANY),
    (0x1018, 0, U8, RO, 4), (0x1018, 1, U32, RO, 0x0000_001D), (0x1018, 2, U32, RO, ANY),
    (0x1018, 3, U32, RO, ANY), (0x1018, 4, U32, RO, ANY),
    (0x10F1, 0, U8, RO, 2), (0x10F1, 1, U32, RO, ANY), (0x10F1, 2, U32, RO, ANY),
    (0x10F3, 0, U8, RO, ANY), (0x10F3, 1, U8, RO, 64), (0x10F3, 2, U8, RO, ANY),
    (0x10F3, 3, U8, RW, ANY), (0x10F3, 4, BOOL, RO, ANY), (0x10F3, 5, U16, RW, 0x0000),
    (0x1A40, 0, U8, RO, 1), (0x1A40, 1, U32, RW, 0x10F3_0401),
    (0x2400, 0, U8, RO, 8), (0x2400, 1, U8, RW, 0x00), (0x2400, 2, BOOL, RW, True),
    (0x2400, 3, BOOL, RW, True), (0x2400, 4, BOOL, RW, True), (0x2400, 5, BOOL, RW, True),
    (0x2400, 6, BOOL, RW, True), (0x2400, 7, U8, RW, 0x00), (0x2400, 8, U8, RW, 0x00),
    (0x2401, 0, U8, RW, ANY),
    (0x5000, 0, U8, RO, 3), (0x5000, 1, U8, RO, 6), (0x5000, 2, U8, RO, 12),
    (0x5000, 3, U8, RO, 10), (0x5001, 0, STR, RO, ANY), (0x5002, 0, STR, RO, ANY),
    (0xF000, 0, U8, RO, 2), (0xF000, 1, U8, RO, 1), (0xF000, 2, U16, RO, 48),
    (0xF050, 0, U16, RO, 6),
]


@pytest.fixture(scope="module")
def od_bench() -> Bench:
    return Bench(TAB9_MODULES, master=False, dil2=True)


@pytest.mark.parametrize(("index", "sub", "dtype", "access", "value"), TAB27,
                         ids=[f"{r[0]:04X}:{r[1]}" for r in TAB27])
def test_tab27(od_bench: Bench, index: int, sub: int, dtype: DataType, access: Access,
               value: Any) -> None:
    entry = od_bench.cpx.od.entry(index, sub)
    assert (entry.dtype, entry.access) == (dtype, access)
    if value is not ANY:
        assert od_bench.apply("read_object", index=index, sub=sub) == value


# Tab. 27 "Описание" of 0x2400 as the seed prints it. Sub 5 is "Monitor V_VEN", the load
# voltage of the valves (German Ventile), not an OCR slip: V_OUT and V_SEN beside it are read
# cleanly, and the name is what a configuration tool shows from the device.
TAB27_2400_NAMES = ["Global CPX Settings", "Filter Alarm V_OUT/V_SEN", "Monitor SCS",
                    "Monitor SCO", "Monitor V_OUT", "Monitor V_VEN", "Monitor SCV", "Fail safe",
                    "System Start"]


def test_tab27_global_settings_names(od_bench: Bench) -> None:
    assert [od_bench.cpx.od.entry(0x2400, sub).name for sub in range(9)] == TAB27_2400_NAMES


def test_new_message_available_is_pdo_mappable(od_bench: Bench) -> None:
    """Tab. 14 "RO P"; 0x1A40 maps it (printed "0x10F3:00,1", read as 0x10F3:04, 1 bit)."""
    assert od_bench.cpx.od.entry(0x10F3, 4).pdo_mappable


@pytest.mark.parametrize(("index", "sub"), [(0x1000, 0), (0x1018, 1), (0x10F3, 1),
                                            (0x10F3, 4), (0x6001, 1), (0xF050, 2)])
def test_read_only_objects_refuse_writes(od_bench: Bench, index: int, sub: int) -> None:
    with pytest.raises(SdoAbort) as info:
        od_bench.apply("write_object", index=index, sub=sub, value=1)
    assert info.value.code is AbortCode.READ_ONLY


def test_missing_objects() -> None:
    bench = Bench(TAB9_MODULES, master=False)
    for index, sub, code in ((0x6000, 1, AbortCode.NO_OBJECT), (0x2200, 0, AbortCode.NO_OBJECT),
                             (0x1018, 5, AbortCode.NO_SUBINDEX)):
        with pytest.raises(SdoAbort) as info:
            bench.apply("read_object", index=index, sub=sub)
        assert info.value.code is code  # no status bits: no module 0 objects; no 4IOL


# Module xx -> (TxPDO entries, RxPDO entries) as "0x60xx:yy,s" / "0x70xx:yy,s" (Tab. 27).
MAPPINGS = [
    (0, [pdo_entry(0x6000, y, 1) for y in range(1, 9)] + [8], []),
    (1, [pdo_entry(0x6001, y, 1) for y in range(1, 17)], []),
    (2, [], [pdo_entry(0x7002, y, 1) for y in range(1, 9)]),
    (3, [], [pdo_entry(0x7003, y, 1) for y in range(1, 9)]),
    (4, [pdo_entry(0x6004, y, 16) for y in range(1, 5)], []),
    (5, [], [pdo_entry(0x7005, y, 16) for y in range(1, 5)]),
]


@pytest.mark.parametrize(("xx", "tx", "rx"), MAPPINGS)
def test_pdo_mapping_per_module(od_bench: Bench, xx: int, tx: list[int],
                                rx: list[int]) -> None:
    """0x1Axx / 0x16xx: sub 0 = yy, entries 0x60xx:yy,s / 0x70xx:yy,s (the status bits'
    second byte is an 8-bit gap, Tab. 28 note 4)."""
    od = od_bench.cpx.od
    for pdo, entries in ((0x1A00 + xx, tx), (0x1600 + xx, rx)):
        if not entries:
            assert not od.has_index(pdo)
            continue
        assert od.read(pdo, 0) == len(entries)
        assert [od.read(pdo, y) for y in range(1, len(entries) + 1)] == entries
        assert od.entry(pdo, 1).access is Access.RW


def test_mapping_entries_keep_their_fixed_value(od_bench: Bench) -> None:
    od_bench.apply("write_object", index=0x1A01, sub=1, value=pdo_entry(0x6001, 1, 1))
    with pytest.raises(SdoAbort) as info:
        od_bench.apply("write_object", index=0x1A01, sub=1, value=pdo_entry(0x6001, 2, 1))
    assert info.value.code is AbortCode.VALUE_RANGE
    assert od_bench.apply("read_object", index=0x1A01, sub=1) == pdo_entry(0x6001, 1, 1)


def test_process_objects_access(od_bench: Bench) -> None:
    """0x60xx RO P, 0x70xx RW P, sub 0 the number of entries."""
    od = od_bench.cpx.od
    assert od.entry(0x6004, 1).access is Access.RO and od.entry(0x6004, 1).pdo_mappable
    assert od.entry(0x7005, 4).access is Access.RW and od.entry(0x7005, 4).pdo_mappable
    assert od.entry(0x7005, 4).dtype is DataType.INTEGER16
    assert (od.read(0x6001, 0), od.read(0x7002, 0), od.read(0x6004, 0)) == (16, 8, 4)
    od_bench.apply("write_object", index=0x7002, sub=3, value=1)
    assert od_bench.cpx.modules[1].out_values[2] == 1
    with pytest.raises(SdoAbort):
        od_bench.apply("write_object", index=0x7002, sub=3, value=2)


def test_module_parameters_and_failsafe(od_bench: Bench) -> None:
    """0x20xx (parameter-dependent: the analog signal ranges), 0x21xx failsafe per channel."""
    assert od_bench.apply("read_object", index=0x2004, sub=0) == 4
    od_bench.apply("write_object", index=0x2004, sub=2, value=6)
    assert od_bench.cpx.modules[3].channel_range(1).name == "4-20mA"
    with pytest.raises(SdoAbort):
        od_bench.apply("write_object", index=0x2004, sub=2, value=3)
    assert od_bench.apply("read_object", index=0x2102, sub=0) == 8
    od_bench.apply("write_object", index=0x2102, sub=8, value=1)
    assert od_bench.cpx.modules[1].failsafe[7] == 1


# Tab. 27 prints "yy Input yy", "yy Output yy", "yy Channel yy", "yy Parameter yy": the
# model names each entry by what it is, its CPX channel counted from 0 (as 0x22xx:2 «Channel
# (Start at 0)» and the 0x10F3 channel parameter count), so sub yy is channel yy - 1
# (docs/cpx-e-ec.md choice 50). The mapping entries keep the sub: "Input Mapping 01".
SUB_NAMES = [(0x6001, 1, "Input 0"), (0x6001, 16, "Input 15"), (0x7002, 8, "Output 7"),
             (0x6004, 1, "Input channel 0"), (0x7005, 4, "Output channel 3"),
             (0x2004, 1, "Signal range channel 0"), (0x2102, 1, "Channel 0"),
             (0x2105, 4, "Channel 3"), (0x6000, 1, "Status bit 0"),
             (0x1A01, 1, "Input Mapping 01"), (0x1602, 8, "Output Mapping 08")]


@pytest.mark.parametrize(("index", "sub", "name"), SUB_NAMES,
                         ids=[f"{r[0]:04X}:{r[1]}" for r in SUB_NAMES])
def test_module_entries_are_named_by_channel_from_0(od_bench: Bench, index: int, sub: int,
                                                    name: str) -> None:
    assert od_bench.cpx.od.entry(index, sub).name == name


def test_detected_module_list(od_bench: Bench) -> None:
    """0xF050: sub 0 the number of modules (bus module included), then one ident each."""
    idents = [BUS_STATUS_BITS.ident] + [module_type(n).ident for n in TAB9_MODULES]
    assert [od_bench.apply("read_object", index=0xF050, sub=s) for s in range(1, 7)] == idents
    assert od_bench.apply("read_object", index=0xF050, sub=48) == 0


# ---- ident check at PREOP -> SAFEOP -----------------------------------------------------
def preop(**kwargs: Any) -> Bench:
    bench = Bench(TAB9_MODULES, master=False, dil2=True, **kwargs)
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.al_state is AlState.PREOP
    return bench


def write_f030(bench: Bench, idents: list[int]) -> None:
    """What the PLC's start-up does in PREOP."""
    bench.apply("write_object", index=0xF030, sub=0, value=len(idents))
    for sub, ident in enumerate(idents, start=1):
        bench.apply("write_object", index=0xF030, sub=sub, value=ident)


def detected(bench: Bench) -> list[int]:
    return [bench.apply("read_object", index=0xF050, sub=s) for s in range(1, 7)]


def texts(bench: Bench) -> list[int]:
    return [m.text_id for _s, m in bench.cpx.history.ordered()]


def test_matching_configuration_passes() -> None:
    bench = preop()
    write_f030(bench, detected(bench))
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_state is AlState.SAFEOP and bench.cpx.al_status_code == 0
    assert texts(bench) == []


def test_f030_not_written_skips_the_check() -> None:
    """Tab. 17 0x3801: the check is skipped (a warning), the transition goes ahead."""
    bench = preop()
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_state is AlState.SAFEOP
    assert texts(bench) == [TEXT_IDENT_SKIPPED]
    bench = preop()
    write_f030(bench, detected(bench))
    bench.apply("inject_fault", fault="f030_not_written")
    bench.cpx.request_state(AlState.SAFEOP)
    assert texts(bench) == [TEXT_IDENT_SKIPPED]


def test_mismatch_refuses_safeop() -> None:
    """Tab. 17 0x3800: PREOP -> SAFEOP refused, AL status code 0x0070, Error blinking."""
    bench = preop()
    configured = detected(bench)
    configured[4] = module_type("16DI").ident  # the PLC expects a 16DI as module 4
    write_f030(bench, configured)
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_state is AlState.PREOP
    assert (bench.cpx.al_status, bench.cpx.al_status_code) == (0x12, 0x0070)
    newest = bench.cpx.history.ordered()[-1][1]
    assert (newest.text_id, newest.params) == (TEXT_IDENT_FAILED, ((DataType.UNSIGNED8, 4),))
    bench.step()
    assert bench.led_state("Error") == ("blinking", "red")


def test_missing_module_is_a_mismatch() -> None:
    bench = preop()
    write_f030(bench, [*detected(bench), module_type("8DO").ident])
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_status_code == 0x0070
    assert bench.cpx.history.ordered()[-1][1].params == ((DataType.UNSIGNED8, 6),)


def test_injected_mismatch_and_dil_change() -> None:
    """By name, and physically: DIL status bits -> none changes the bus module's ident."""
    bench = preop()
    bench.apply("inject_fault", module=2, fault="module_ident_mismatch")
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_status_code == 0x0070
    bench = preop()
    configured = detected(bench)
    bench.apply("set_dil", dil1=False, dil2=False)
    bench.apply("restart")
    bench.cpx.request_state(AlState.PREOP)
    write_f030(bench, configured)
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_status_code == 0x0070
    assert bench.cpx.history.ordered()[-1][1].params == ((DataType.UNSIGNED8, 0),)


def test_replacing_a_module_needs_the_power_off() -> None:
    bench = preop()
    configured = detected(bench)
    with pytest.raises(Exception, match="switched off"):
        bench.apply("replace_module", module=1, type="8DO")
    bench.apply("power", on=False)
    bench.run(0.05)
    bench.apply("replace_module", module=1, type="8DO")
    bench.apply("power", on=True)
    assert detected(bench)[1] == module_type("8DO").ident
    bench.cpx.request_state(AlState.PREOP)
    write_f030(bench, configured)
    bench.cpx.request_state(AlState.SAFEOP)
    assert bench.cpx.al_status_code == 0x0070


def test_built_in_master_reaches_op_with_the_skip_warning() -> None:
    """The built-in master does not write 0xF030: one 0x3801 per PREOP -> SAFEOP."""
    bench = tab9().to_op()
    assert texts(bench) == [TEXT_IDENT_SKIPPED]
