"""Outputs on a communication error in OP: 0xF700 / 0xF701 per slot kind (seed 001 §9.3.5)
and the 0xF710 SysOK mask (§9.3.6), as rules and through the device."""

from __future__ import annotations

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.trscat.catalog import EXPANSIONS, INTEGRATED
from devices.trscat.outputs import outputs_on_error

IO_E, AN_E, AC_E, XX_E, KK_E = (EXPANSIONS[n] for n in
                                ("TRS-IO-E", "TRS-AN-E", "TRS-AC-E", "TRS-XX-E", "TRS-KK-E"))
HELD16 = [1, 0] * 8

# (kind, held, ErrorMode, ErrorVal, expected) — §9.3.5 per kind.
RULES = [
    # integrated / TRS-IO-E: each ErrorMode bit: 0 = hold, 1 = the ErrorVal bit.
    (INTEGRATED, HELD16, 0x0000, 0xFFFF, HELD16),  # reset default: hold (pre-01.20 default)
    (INTEGRATED, HELD16, 0xFFFF, 0x0000, [0] * 16),
    (INTEGRATED, HELD16, 0xFFFF, 0xFFFF, [1] * 16),
    (INTEGRATED, HELD16, 0x000F, 0x0006, [0, 1, 1, 0, *HELD16[4:]]),
    (IO_E, HELD16, 0x8001, 0x8000, [0, *HELD16[1:15], 1]),
    # TRS-AN-E / generic standard: only ErrorMode 0xFFFF uses ErrorVal, for every output.
    (AN_E, [100, -200], 0xFFFF, 0x1234, [0x1234, 0x1234]),
    (AN_E, [100, -200], 0xFFFF, 0xFC18, [-1000, -1000]),  # U16 ErrorVal on INT16 outputs
    (AN_E, [100, -200], 0xFFFE, 0x1234, [100, -200]),  # any other value: hold
    (AN_E, [100, -200], 0x0000, 0x1234, [100, -200]),
    (XX_E, [7], 0xFFFF, 0xBEEF, [0xBEEF]),
    (XX_E, [7], 0x00FF, 0xBEEF, [7]),
    # TRS-AC-E / generic smart: the objects are ignored, always hold.
    (AC_E, [1, 2, 3, 4], 0xFFFF, 0, [1, 2, 3, 4]),
    (KK_E, [1, 2, 3, 4], 0xFFFF, 0xFFFF, [1, 2, 3, 4]),
]


@pytest.mark.parametrize(("kind", "held", "mode", "value", "expected"), RULES,
                         ids=[f"{r[0].short}-{r[2]:04X}-{r[3]:04X}" for r in RULES])
def test_error_rules(kind, held, mode, value, expected) -> None:
    """§9.3.5 per expansion kind."""
    assert outputs_on_error(kind, held, mode, value) == expected


@pytest.mark.parametrize(("mode", "value", "sysok", "expected"), [
    (0x0000, 0x0000, 0x0001, [0, *HELD16[1:]]),  # SysOK bit 1: logic 0
    (0xFFFF, 0xFFFF, 0x0003, [0, 0] + [1] * 14),  # overrides 0xF700 / 0xF701
    (0x0000, 0x0000, 0x0000, HELD16),  # 0 at reset: hold
])
def test_sysok_mask_overrides(mode: int, value: int, sysok: int, expected: list[int]) -> None:
    """§9.3.6: a 1 in 0xF710 forces that integrated output to 0 whatever 0xF700/0xF701 say."""
    assert outputs_on_error(INTEGRATED, HELD16, mode, value, sysok) == expected


def test_sysok_mask_is_for_the_integrated_module_only() -> None:
    """§9.3.6: the SysOK property is for the outputs of the integrated expansion."""
    assert outputs_on_error(IO_E, HELD16, 0, 0, sysok_mask=0xFFFF) == HELD16


# ---- through the device ----------------------------------------------------------------------
def _op_with_pattern(**kw) -> Bench:
    bench = Bench(["IO-E", "AN-E", "KK-E"], configured=["IO-E", "AN-E", "KK-E"], **kw)
    bench.to_state(AlState.OP)
    for ch in range(1, 17):
        bench.apply("set_output", channel=ch, value=ch % 2)
        bench.apply("set_output", module=1, channel=ch, value=1)
    bench.apply("set_output", module=2, channel=1, value=300)
    bench.apply("set_output", module=3, channel=4, value=9)
    bench.run(0.005)
    return bench


def test_comm_error_in_op_defaults_to_hold() -> None:
    """§9.3.5: with 0 everywhere (reset default) every output keeps its last value."""
    bench = _op_with_pattern()
    held = [list(io.applied) for io in bench.trs.rail]
    bench.apply("link", port="in", connected=False)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status == 0x14
    assert [io.applied for io in bench.trs.rail] == held


def test_comm_error_in_op_uses_the_objects() -> None:
    """§9.3.5 / §9.3.6 on a sync error in OP: each slot by its kind, SysOK over all."""
    bench = _op_with_pattern()
    bench.write(0xF701, 1, 0x00F0)  # integrated: I/O 5..8 take ErrorVal0
    bench.write(0xF700, 1, 0x00A0)  # bits 4..7 = 0, 1, 0, 1 (held there: 1, 0, 1, 0)
    bench.write(0xF710, 1, 0x0001)  # I/O 1 forced to 0
    bench.write(0xF701, 2, 0x0001)  # TRS-IO-E: output 1 takes ErrorVal1 bit 0 = 0
    bench.write(0xF701, 3, 0xFFFF)  # TRS-AN-E: all outputs take ErrorVal2
    bench.write(0xF700, 3, 0x0064)
    bench.write(0xF701, 4, 0xFFFF)  # TRS-KK-E: ignored
    bench.apply("drop_frames", count=10)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0x001A
    base, io_e, an_e, kk_e = (io.applied for io in bench.trs.rail)
    assert base[:8] == [0, 0, 1, 0, 0, 1, 0, 1]
    assert base[8:] == [1, 0] * 4
    assert io_e == [0] + [1] * 15
    assert an_e == [100, 100]
    assert kk_e == [0, 0, 0, 9]
    assert bench.trs.snapshot()["outputs_mode"] == "error"


def test_requested_safeop_is_the_safe_state_not_the_error_values() -> None:
    """§9.2: a SAFE-OP the master asks for puts the outputs in the safe state (off); the
    0xF700 / 0xF701 values are for the communication errors only (§9.3.5)."""
    bench = _op_with_pattern()
    bench.write(0xF701, 1, 0xFFFF)
    bench.write(0xF700, 1, 0xFFFF)
    bench.request(AlState.SAFEOP)
    bench.run(0.003)
    assert bench.trs.rail[0].applied == [0] * 16


def test_back_to_op_follows_the_master_again() -> None:
    bench = _op_with_pattern()
    bench.apply("drop_frames", count=5)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP
    bench.request(AlState.OP)
    bench.run(0.003)
    assert bench.trs.al_state is AlState.OP
    assert bench.trs.rail[0].applied == [ch % 2 for ch in range(1, 17)]


# ---- the output image of a state change, whether or not a local cycle follows ---------------
def _op_with_io1_on(sysok: int) -> Bench:
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.write(0xF710, 1, sysok)
    bench.apply("set_output", channel=1, value=1)
    bench.run(0.01)
    assert bench.trs.rail[0].applied[0] == 1 and bench.leds()["I/O 1"] == "on"
    return bench


def _io1(bench: Bench) -> tuple[int, bool, str]:
    """I/O 1 as commanded, as driven on the terminal, as lit (§8.3)."""
    snap = bench.trs.snapshot()
    return (snap["slots"][0]["outputs"][0], snap["slots"][0]["lines"][0]["driving"],
            snap["leds"]["I/O 1"])


@pytest.mark.parametrize(("sysok", "io1"), [(0x0001, (0, False, "off")),
                                            (0x0000, (1, True, "on"))])
def test_fatal_sync_error_applies_the_error_outputs_without_sync0(
        sysok: int, io1: tuple[int, bool, str]) -> None:
    """§9.3.6: on a communication error in OP (here the fatal sync error 0x002C: SYNC0 stops)
    a 0xF710 bit 1 puts that output to logic 0; bit 0 holds it (§9.3.5). The state change
    applies the outputs: no local cycle follows, SYNC0 being gone (§9.1.1)."""
    bench = _op_with_io1_on(sysok)
    bench.apply("lose_sync0", lost=True)
    bench.run(0.5)
    assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.SAFEOP, 0x002C)
    assert bench.trs.snapshot()["outputs_mode"] == "error"
    assert _io1(bench) == io1
    bench.request(AlState.SAFEOP)  # the master acknowledges the error: outputs as they are
    bench.run(0.5)
    assert _io1(bench) == io1


def test_requested_safeop_without_sync0_is_the_safe_state() -> None:
    """§9.2 SAFE-OP: "gli Output rimangono in 'safe-state'", from the request on, with SYNC0
    lost before the device noticed (no local cycle runs any more)."""
    bench = _op_with_io1_on(0)
    bench.apply("lose_sync0", lost=True)
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_state is AlState.SAFEOP
    assert _io1(bench) == (0, False, "off")
    bench.run(0.5)
    assert bench.trs.snapshot()["outputs_mode"] == "safe"
    assert _io1(bench) == (0, False, "off")


@pytest.mark.parametrize("wait_s", [0.0, 0.5])
def test_master_switching_sync0_off_then_leaving_op(wait_s: float) -> None:
    """The master writes 0x0981 = 0 in OP (SYNC0 off, §9.1.1) and then asks for SAFE-OP, at
    once or after the fatal sync error it caused: the outputs are off from the request on."""
    bench = _op_with_io1_on(0)
    bench.configure_dc(0, bench.step_us * 1000)
    bench.run(wait_s)
    bench.trs.request_state(AlState.SAFEOP)  # not bench.request: it would write SYNC0 on
    bench.run(0.5)
    assert bench.trs.al_state is AlState.SAFEOP
    assert bench.trs.snapshot()["outputs_mode"] == ("error" if wait_s else "safe")
    # After the fall the request acknowledges the error and the held outputs stay (§9.3.5
    # hold, 0xF710 = 0); without the fall it is the safe state.
    assert _io1(bench) == ((1, True, "on") if wait_s else (0, False, "off"))
    bench.trs.request_state(AlState.PREOP)
    assert _io1(bench) == (0, False, "off")


# ---- TRS bus shutdown: every module stops at once, SYNC0 or not ------------------------------
def _driven(bench: Bench) -> list[tuple[list[int], bool, list[int]]]:
    """Per digital slot: outputs applied, any line driven, the TxPDO inputs image."""
    out = []
    for io in bench.trs.rail:
        if io is not None and io.lines is not None:
            out.append((list(io.applied), io.lines.driving != 0, list(io.inputs)))
    return out


def _op_dc_with_outputs_on() -> Bench:
    bench = Bench(["IO-E", "IO-E"], configured=["IO-E", "IO-E"])
    bench.to_state(AlState.OP)
    for module in (None, 1, 2):
        bench.apply("set_output", module=module, channel=1, value=1)
    bench.run(0.01)
    assert all(applied[0] == 1 and driving for applied, driving, _ in _driven(bench))
    assert bench.leds()["I/O 1"] == "on"
    return bench


def _stop_sync0(bench: Bench, how: str) -> None:
    if how == "lose_sync0":
        bench.apply("lose_sync0", lost=True)
    elif how == "0x0981=0":  # the master switches SYNC0 off (§9.1.1)
        bench.configure_dc(0, bench.step_us * 1000)


SHUTDOWNS = [("inject_fault", {"fault": "TRS_UNDERVOLTAGE"}),
             ("inject_fault", {"fault": "TRS_OVERCURRENT"}),
             ("inject_fault", {"fault": "TRS_COMM_ERROR"}),
             ("unplug", {"module": 2})]  # §7: unplugged under power, 0x7500


@pytest.mark.parametrize("how", ["lose_sync0", "0x0981=0"])
@pytest.mark.parametrize("fall", [True, False], ids=["after-the-fall", "still-in-op"])
@pytest.mark.parametrize(("action", "args"), SHUTDOWNS, ids=lambda v: str(v))
def test_bus_shutdown_stops_every_module_without_sync0(how: str, fall: bool, action: str,
                                                       args: dict) -> None:
    """§9.3.7 "shutdown irreversibile del bus TRS", §8.2: the modules stop at the shutdown,
    outputs off and inputs 0, as the leaving of OP puts its outputs out at once: in DC-SYNC no
    local cycle follows while SYNC0 is lost or off (§9.1.1). Here the outputs are held by the
    fatal sync error (0xF710 = 0, §9.3.5 hold) or still those of OP."""
    bench = _op_dc_with_outputs_on()
    _stop_sync0(bench, how)
    bench.run(0.5 if fall else 0.001)
    assert bench.trs.al_state is (AlState.SAFEOP if fall else AlState.OP)
    assert _driven(bench)[0][:2] == ([1] + [0] * 15, True)  # held (or OP): I/O 1 still on
    bench.apply(action, **args)
    bench.step()
    assert bench.trs.snapshot()["trs_bus"]["state"] == "shutdown"
    for applied, driving, inputs in _driven(bench):
        assert (applied, driving, inputs) == ([0] * 16, False, [0] * 16)
    assert bench.leds()["I/O 1"] == "off"
    bench.run(0.5)
    assert bench.leds()["I/O 1"] == "off" and not any(d for _, d, _ in _driven(bench))
