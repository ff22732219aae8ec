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


@pytest.mark.parametrize(("mode", "value", "volts"), [
    (0x0000, 0x0000, 5.0),  # reset default: hold the last value the master sent
    (0xFFFF, 0xE000, -2.5),  # 0xFFFF: ErrorVal2 (INT16 -8192), whatever was held
])
def test_a_module_not_driving_at_the_fall_holds_the_masters_value(
        mode: int, value: int, volts: float) -> None:
    """§9.3.5 "gli output (sia digitali che analogici) mantengano l'ultimo stato noto": the
    last value known is the master's, not the 0 V of a TRS-AN-E whose ±12 V supply (0x5114,
    §9.3.7) was out when the communication error came. Its supply back, it drives that value,
    as it does in OP."""
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    bench.write(0xF701, 2, mode)
    bench.write(0xF700, 2, value)
    bench.apply("set_output", module=1, channel=1, value=0x4000)  # +5 V
    bench.run(0.01)
    bench.apply("inject_fault", module=1, fault="AN_PLUS_12V")
    bench.run(0.01)
    assert bench.trs.snapshot()["slots"][1]["analog_out_v"][0] == 0.0
    bench.apply("drop_frames", count=10)
    bench.run(0.01)
    assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.SAFEOP, 0x001A)
    bench.apply("clear_fault", module=1, fault="AN_PLUS_12V")
    bench.run(0.01)
    assert bench.trs.snapshot()["slots"][1]["analog_out_v"][0] == pytest.approx(volts, abs=1e-3)


def test_requested_safeop_is_the_safe_state_not_the_error_values() -> None:
    """§9.2: a SAFE-OP the master asks for puts the outputs in the safe state (off); the
    0xF700 / 0xF701 values are for the communication errors only (§9.3.5)."""
    bench = _op_with_pattern()
    bench.write(0xF701, 1, 0xFFFF)
    bench.write(0xF700, 1, 0xFFFF)
    bench.request(AlState.SAFEOP)
    bench.run(0.003)
    assert bench.trs.rail[0].applied == [0] * 16


@pytest.mark.parametrize("request_", ("boot", "unknown"))
def test_a_request_refused_in_op_drops_to_safeop_in_the_safe_state(request_: str) -> None:
    """ETG.1000.6 (SSC AL_ControlInd, SOES ESC_state): a request refused in OP (BOOT: 0x0011,
    an invalid transition from OP; an unknown state: 0x0012) leaves the device in SAFE-OP +
    error. No communication error (§9.3.5 / §9.3.6 are for those only): the outputs go to the
    safe state of a requested SAFE-OP (§9.2), not to the 0xF700 / 0xF701 values."""
    bench = _op_with_pattern()
    bench.write(0xF701, 1, 0xFFFF)
    bench.write(0xF700, 1, 0xFFFF)
    if request_ == "boot":
        bench.trs.request_state(AlState.BOOT)
    else:  # AL control 0x05, as the wire face hands it to the ESM
        bench.trs.esm.request_unknown(0x05, False, bench.trs.now_us)
    bench.run(0.003)
    code = 0x0011 if request_ == "boot" else 0x0012
    trs = bench.trs
    assert (trs.al_state, trs.al_status, trs.al_status_code) == (AlState.SAFEOP, 0x14, code)
    assert trs.rail[0].applied == [0] * 16
    assert trs.snapshot()["outputs_mode"] == "safe"
    assert bench.leds()["ERROR"] == "blinking"


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
    # Not bench.request: it would write SYNC0 on. A master acknowledges the flag it reads.
    bench.trs.request_state(AlState.SAFEOP, ack=bool(bench.trs.al_status & 0x10))
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


# ---- the field supply without SYNC0: the output drivers follow it at once --------------------
# (cut, restore) of the base's +24Vdc: out of range, or its check failing (0x3220 on the base).
SUPPLY = {"field_supply": (("field_supply", {"volts": 0.0}), ("field_supply", {"volts": 24.0})),
          "0x3220": (("inject_fault", {"fault": "0x3220"}), ("clear_fault", {"fault": "0x3220"}))}


def _terminals(bench: Bench) -> list[tuple[list[int], int]]:
    """Per digital slot: the outputs it holds and the lines its driver really drives."""
    return [(list(io.applied), io.lines.driving) for io in bench.trs.rail
            if io is not None and io.lines is not None]


def _powered(held: list[tuple[list[int], int]]) -> list[tuple[list[int], int]]:
    return [(applied, sum(v << i for i, v in enumerate(applied))) for applied, _ in held]


@pytest.mark.parametrize("how", ["lose_sync0", "0x0981=0"])
@pytest.mark.parametrize("fall", [True, False], ids=["after-the-fall", "still-in-op"])
@pytest.mark.parametrize("supply", list(SUPPLY))
def test_field_supply_switches_the_drivers_without_sync0(how: str, fall: bool,
                                                         supply: str) -> None:
    """§10.3: the base's +24Vdc "viene utilizzata per il driver degli output" (and feeds the
    expansions over the TRS bus): without it no output is driven, whether or not a local
    cycle comes, and in DC-SYNC none does while SYNC0 is lost or off (§9.1.1). The module
    keeps its image (held by the fatal sync error, §9.3.5, or still OP's): with the supply
    back it is driven again, without new outputs from the master (taken only at a cycle)."""
    bench = _op_dc_with_outputs_on()
    _stop_sync0(bench, how)
    bench.run(0.5 if fall else 0.001)
    state = AlState.SAFEOP if fall else AlState.OP
    assert bench.trs.al_state is state
    held = _terminals(bench)
    assert held == _powered(held) and held[0][0] == [1] + [0] * 15
    bench.apply("set_output", channel=2, value=1)  # the master's new data: waits for a cycle
    (cut, cut_args), (restore, restore_args) = SUPPLY[supply]
    bench.apply(cut, **cut_args)
    bench.step()
    assert bench.trs.al_state is state
    assert _terminals(bench) == [(applied, 0) for applied, _ in held]
    assert (bench.leds()["I/O 1"], bench.leds()["+24V"]) == ("off", "off")
    bench.apply(restore, **restore_args)
    bench.step()
    assert _terminals(bench) == held
    assert (bench.leds()["I/O 1"], bench.leds()["+24V"]) == ("on", "on")
    bench.run(0.5)
    assert _terminals(bench) == held and bench.leds()["I/O 1"] == "on"


@pytest.mark.parametrize("how", ["lose_sync0", "0x0981=0"])
def test_field_supply_back_after_sync0_lost_drives_the_held_image(how: str) -> None:
    """The supply went while SYNC0 ran (the local cycle took the drivers off), then SYNC0 went
    and the fatal sync error held the outputs (§9.3.5): the supply back drives them at once."""
    bench = _op_dc_with_outputs_on()
    held = _terminals(bench)
    bench.apply("field_supply", volts=0.0)
    bench.run(0.01)
    assert _terminals(bench) == [(applied, 0) for applied, _ in held]
    _stop_sync0(bench, how)
    bench.run(0.5)
    assert bench.trs.al_state is AlState.SAFEOP
    bench.apply("field_supply", volts=24.0)
    bench.step()
    assert _terminals(bench) == held
    assert (bench.leds()["I/O 1"], bench.leds()["+24V"]) == ("on", "on")


def test_field_supply_back_without_sync0_drives_the_error_image() -> None:
    """After the fatal sync error the module holds its error image (§9.3.6: 0xF710 bit 1 puts
    I/O 1 to 0, I/O 2 held, §9.3.5): the supply back drives that image, not OP's."""
    bench = _op_with_io1_on(0x0001)
    bench.apply("set_output", channel=2, value=1)
    bench.run(0.01)
    bench.apply("lose_sync0", lost=True)
    bench.run(0.5)
    assert bench.trs.snapshot()["outputs_mode"] == "error"
    assert bench.trs.rail[0].latched[:2] == [1, 1]  # OP's image, still latched
    image = ([0, 1] + [0] * 14, 0b10)
    assert _terminals(bench) == [image]
    bench.apply("field_supply", volts=0.0)
    bench.step()
    assert _terminals(bench) == [(image[0], 0)]
    bench.apply("field_supply", volts=24.0)
    bench.step()
    assert _terminals(bench) == [image]
    assert (bench.leds()["I/O 1"], bench.leds()["I/O 2"]) == ("off", "on")


def test_an_e_supply_fault_without_sync0_stops_the_module_at_once() -> None:
    """0x5114 (§9.3.7) on a TRS-AN-E stops that module (outputs 0 V, inputs 0): like the field
    supply, its own supply failing does not wait for a SYNC0; cleared, the held image is out
    again. The TxPDO inputs wait for a local cycle (none while SYNC0 is lost, §9.1.1)."""
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    bench.apply("set_output", module=1, channel=1, value=1000)
    bench.apply("set_analog_input", module=1, channel=1, volts=5.0)
    bench.run(0.01)
    bench.apply("lose_sync0", lost=True)
    bench.run(0.5)
    an_e = bench.trs.rail[1]
    assert bench.trs.al_state is AlState.SAFEOP and an_e.applied == [1000, 0]
    inputs = list(an_e.inputs)
    assert inputs[0] > 0
    bench.apply("inject_fault", module=1, fault="AN_PLUS_12V")
    bench.run(0.002)  # the alarm is raised, then the module stops (as at a local cycle)
    assert (an_e.applied, an_e.inputs) == ([0, 0], [0] * len(inputs))
    bench.apply("clear_fault", module=1, fault="AN_PLUS_12V")
    bench.run(0.002)
    assert (an_e.applied, an_e.inputs) == ([1000, 0], [0] * len(inputs))


# (cut, restore) of a TRS-AN-E's field supply at slot 1: the base's +24Vdc out of range, its
# check failing (0x3220 on the base), or the module's own (0x3220 on slot 1).
AN_E_SUPPLY = {**SUPPLY, "0x3220@1": (("inject_fault", {"fault": "0x3220", "module": 1}),
                                      ("clear_fault", {"fault": "0x3220", "module": 1}))}


@pytest.mark.parametrize("sync0", [True, False], ids=["sync0", "sync0-lost"])
@pytest.mark.parametrize("supply", list(AN_E_SUPPLY))
def test_an_e_outputs_need_the_field_supply(supply: str, sync0: bool) -> None:
    """§10.3: the +24Vdc "viene utilizzata per il driver degli output" and reaches the
    expansions over the TRS bus; §9.3.7 0x3220 "su modulo TRS-nn-E o su base". Without it a
    TRS-AN-E drives no voltage, as a digital line drives nothing: its terminals read 0 V while
    the module keeps the master's image, and the value is back with the supply, local cycle
    or not."""
    bench = Bench(["AN-E"], configured=["AN-E"])
    bench.to_state(AlState.OP)
    bench.apply("set_output", module=1, channel=1, value=-0x4000)  # -5 V
    bench.run(0.01)
    if not sync0:
        bench.apply("lose_sync0", lost=True)
        bench.run(0.5)
    slot = bench.trs.snapshot()["slots"][1]
    assert slot["analog_out_v"] == [pytest.approx(-5.0, abs=1e-3), 0.0]
    (cut, cut_args), (restore, restore_args) = AN_E_SUPPLY[supply]
    bench.apply(cut, **cut_args)
    bench.step()
    slot = bench.trs.snapshot()["slots"][1]
    assert (slot["outputs"], slot["analog_out_v"]) == ([-0x4000, 0], [0.0, 0.0])
    bench.apply(restore, **restore_args)
    bench.step()
    slot = bench.trs.snapshot()["slots"][1]
    assert slot["analog_out_v"] == [pytest.approx(-5.0, abs=1e-3), 0.0]
