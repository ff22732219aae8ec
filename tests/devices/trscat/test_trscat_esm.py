"""The TRS-CAT EtherCAT state machine (seed 001 §9.2), 0xF030 / 0xF050 and the slot
configuration check (§9.3.2), the automatic PDO assignment (§9.3.2 footnote 4, §9.3.3)."""

from __future__ import annotations

import pytest
from trscat_bench import Bench, detect_us

from devices.ethercat import ALLOWED_TRANSITIONS, AlState
from devices.od import AbortCode, SdoAbort
from devices.trscat.catalog import ascii_ident
from devices.trscat.esm import TRANSITION_CHECKS
from devices.trscat.transitions import ident_mismatch

ESM_STATES = (AlState.INIT, AlState.PREOP, AlState.SAFEOP, AlState.OP)
IO_B, IO_E, AN_E, KK_E = (ascii_ident(t) for t in ("IO-B", "IO-E", "AN-E", "KK-E"))


@pytest.mark.parametrize("current", ESM_STATES)
@pytest.mark.parametrize("target", (*ESM_STATES, AlState.BOOT))
def test_esm_requests(current: AlState, target: AlState) -> None:
    """ETG.1000.6 transitions; others answer 0x0011, INIT -> BOOT 0x0013 "Bootstrap not
    supported" (§9.2 has no BOOT). §9.2 follows "the ETG specifications": ETG.1000.6 gives 0x0013
    to INIT -> BOOT only, PREOP / SAFEOP / OP -> BOOT are invalid transitions (0x0011)."""
    bench = Bench()
    if current is AlState.INIT:
        bench.settle()
    else:
        bench.to_state(current)
    bench.request(target)
    trs = bench.trs
    if target is AlState.BOOT:
        # A refusal in OP lands in SAFEOP (ETG.1000.6; SSC AL_ControlInd, SOES ESC_state).
        left = AlState.SAFEOP if current is AlState.OP else current
        code = 0x0013 if current is AlState.INIT else 0x0011
        assert (trs.al_state, trs.al_status_code) == (left, code)
        assert trs.al_status & 0x10
    elif target is current or (current, target) in ALLOWED_TRANSITIONS:
        assert trs.al_state is target and trs.al_status == int(target)
    else:
        assert (trs.al_state, trs.al_status_code) == (current, 0x0011)
        assert bench.leds()["ERROR"] == "blinking"


def test_checks_table_names_existing_checks() -> None:
    """§9.2: every check of the table is a method of the device."""
    bench = Bench()
    for checks in TRANSITION_CHECKS.values():
        for name in checks:
            assert callable(getattr(bench.trs, name))


@pytest.mark.parametrize(("state", "run"), [
    (AlState.INIT, "off"), (AlState.PREOP, "blinking"), (AlState.SAFEOP, "single_flash"),
    (AlState.OP, "on")])
def test_run_led(state: AlState, run: str) -> None:
    """§8.1 -> ETG.1300 RUN indicator."""
    bench = Bench()
    if state is AlState.INIT:
        bench.settle()
    else:
        bench.to_state(state)
    assert bench.leds()["RUN"] == run


def test_init_to_preop_waits_for_the_detection() -> None:
    """§9.2 INIT: the device reads the TRS bus configuration first; no mailbox before."""
    bench = Bench(["IO-E", "AN-E"])
    bench.request(AlState.PREOP)
    bench.run_until(lambda: bench.trs.al_state is AlState.PREOP)
    assert bench.now == detect_us(3)
    assert bench.leds()["BUS"] == "on"


def test_detected_list() -> None:
    """§9.3.2 0xF050: sub 0 = slots occupied, sub 1 = integrated, then the expansions."""
    bench = Bench(["IO-E", "AN-E", "KK-E"])
    bench.settle()
    assert [bench.read(0xF050, s) for s in range(9)] == [4, IO_B, IO_E, AN_E, KK_E, 0, 0, 0, 0]
    with pytest.raises(SdoAbort) as info:
        bench.write(0xF050, 1, IO_B)
    assert info.value.code is AbortCode.READ_ONLY


def test_configured_list_defaults() -> None:
    """§9.3.2 0xF030: sub 0 default 1, sub 1 default 0x494F2D42."""
    bench = Bench(["IO-E"])
    bench.settle()
    assert bench.read(0xF030, 0) == 1 and bench.read(0xF030, 1) == IO_B


@pytest.mark.parametrize(("state", "ok"), [
    (AlState.PREOP, True), (AlState.SAFEOP, False), (AlState.OP, False)])
def test_configured_list_written_in_preop_only(state: AlState, ok: bool) -> None:
    """§9.3.2: 0xF030 "RO e WRITE in PRE-OP" (printed R-WPS)."""
    bench = Bench()
    bench.to_state(state)
    if ok:
        bench.write(0xF030, 2, IO_E)
        assert bench.read(0xF030, 2) == IO_E
    else:
        with pytest.raises(SdoAbort) as info:
            bench.write(0xF030, 2, IO_E)
        assert info.value.code is AbortCode.CANNOT_STORE_STATE


_TOO_LOW, _TOO_HIGH, _RANGE = AbortCode.VALUE_TOO_LOW, AbortCode.VALUE_TOO_HIGH, \
    AbortCode.VALUE_RANGE


@pytest.mark.parametrize(("sub", "value", "error"), [
    (0, 0, _TOO_LOW), (0, 1, None), (0, 8, None), (0, 9, _TOO_HIGH),  # "valori da 1 a 8"
    (1, IO_B, None), (1, IO_E, _RANGE), (1, 0, _RANGE),  # "ammesso solo 0x494F2D42"
    (2, KK_E, None), (8, KK_E, _RANGE), (8, AN_E, None), (3, 0, None), (4, 0x1234, _RANGE)])
def test_configured_list_values(sub: int, value: int, error: AbortCode | None) -> None:
    """§9.3.2 0xF030 table: the allowed values of each sub (0 only for an unused expansion
    sub: sub 1, the integrated module, admits 0x494F2D42 alone)."""
    bench = Bench()
    bench.to_state(AlState.PREOP)
    if error is None:
        bench.write(0xF030, sub, value)
        assert bench.read(0xF030, sub) == value
    else:
        before = bench.read(0xF030, sub)
        with pytest.raises(SdoAbort) as info:
            bench.write(0xF030, sub, value)
        assert info.value.code is error
        assert bench.read(0xF030, sub) == before


def _write_f030(bench: Bench, idents: list[int]) -> None:
    bench.write(0xF030, 0, len(idents))
    for sub, ident in enumerate(idents, start=1):
        bench.write(0xF030, sub, ident)


@pytest.mark.parametrize(("configured", "slot"), [
    ([IO_B, IO_E, AN_E], None),
    ([IO_B, IO_E], 2),  # one expansion missing in the master's list
    ([IO_B, IO_E, AN_E, IO_E], 3),  # one too many
    ([IO_B, AN_E, IO_E], 1),  # order differs
    ([IO_B], 1),  # the master wrote nothing: the default
])
def test_ps_compares_configured_and_detected(configured: list[int], slot: int | None) -> None:
    """§9.2 PS: "0xF030 = 0xF050"; a mismatch refuses SAFE-OP with AL 0x0070 (the code of
    seed 000 §7.7) and makes the configuration error 0xA000 (§9.3.7) with the slot."""
    bench = Bench(["IO-E", "AN-E"])
    bench.to_state(AlState.PREOP)
    if configured != [IO_B]:
        _write_f030(bench, configured)
    assert ident_mismatch([len(configured), *configured], bench.trs.f050) == slot
    bench.request(AlState.SAFEOP)
    trs = bench.trs
    if slot is None:
        assert trs.al_state is AlState.SAFEOP and not bench.messages()
        return
    assert (trs.al_state, trs.al_status, trs.al_status_code) == (AlState.PREOP, 0x12, 0x0070)
    assert bench.leds()["ERROR"] == "blinking"
    [message] = bench.messages()
    assert (message["diag_code"], message["params"]) == ("0xE800A000", [slot])
    [alarm] = bench.records("alarm")
    assert (alarm["code"], alarm["name"], alarm["active"]) == ("0xA000", "CONFIG_ERROR", True)
    # Fixed by the master: SAFE-OP, the configuration error is gone.
    _write_f030(bench, [IO_B, IO_E, AN_E])
    bench.request(AlState.SAFEOP)
    assert trs.al_state is AlState.SAFEOP
    assert bench.records("alarm")[-1]["active"] is False


def test_pdo_assignment_follows_the_configured_list() -> None:
    """§9.3.2 footnote 4 / §9.3.3: writing 0xF030 implies 0x1C12 / 0x1C13, read-only; 0x1AFF
    first, as a configurator lists a modular device's own PDO (docs/trscat.md "ESI")."""
    bench = Bench(["IO-E", "AN-E"])
    bench.to_state(AlState.PREOP)
    assert [bench.read(0x1C12, s) for s in range(2)] == [1, 0x1600]
    assert [bench.read(0x1C13, s) for s in range(3)] == [2, 0x1AFF, 0x1A00]
    _write_f030(bench, [IO_B, IO_E, AN_E])
    assert [bench.read(0x1C12, s) for s in range(4)] == [3, 0x1600, 0x1601, 0x1602]
    assert [bench.read(0x1C13, s) for s in range(5)] == [4, 0x1AFF, 0x1A00, 0x1A01, 0x1A02]
    with pytest.raises(SdoAbort) as info:
        bench.write(0x1C12, 1, 0x1601)
    assert info.value.code is AbortCode.READ_ONLY


def test_preop_keeps_the_default_list_until_the_master_writes_it_at_ps() -> None:
    """§9.3.2: sub 0 "Default 1", sub 1 0x494F2D42 "(default)"; the list is the master's, sent
    "durante la transizione PS" (§9.2, §9.3.2). The device writes nothing there itself."""
    bench = Bench(["IO-E", "AN-E"], configured=["IO-E", "AN-E"])
    bench.to_state(AlState.PREOP)
    assert bench.trs.f030[:3] == [1, IO_B, 0]
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_state is AlState.SAFEOP
    assert bench.trs.f030[:4] == [3, IO_B, IO_E, AN_E]


def test_built_in_master_brings_it_to_op() -> None:
    """The devices/master.py Slave protocol end to end."""
    bench = Bench(["IO-E", "XX-E"], configured=["IO-E", "XX-E"], master=True)
    bench.run(1.0)
    assert bench.trs.al_state is AlState.OP
    assert [r["to"] for r in bench.records("state") if "machine" not in r] == \
        ["PREOP", "SAFEOP", "OP"]


def test_built_in_master_logs_the_mismatch() -> None:
    bench = Bench(["IO-E"], master=True)
    bench.run(1.0)
    assert bench.trs.al_state is AlState.PREOP
    logs = [r["text"] for r in bench.records("log") if r["device"] == "master"]
    assert any("'PREOP to SAFEOP' failed!" in t and "AL Status Code '0x0070'" in t
               for t in logs)


def test_the_error_flag_is_acknowledged_with_al_control_bit_4() -> None:
    """ETG.1000.6 "Error Ind Ack" (SSC AL_ControlInd): a request without bit 4 over the
    error flag is ignored; the state requested again with it clears flag and code."""
    bench = Bench(["IO-E"])
    bench.to_state(AlState.PREOP)
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_status == 0x12
    code = bench.trs.al_status_code
    bench.trs.request_state(AlState.PREOP)
    assert (bench.trs.al_status, bench.trs.al_status_code) == (0x12, code)
    assert bench.leds()["ERROR"] != "off"
    bench.trs.request_state(AlState.PREOP, ack=True)
    assert bench.trs.al_status == 0x02 and bench.trs.al_status_code == 0
    assert bench.leds()["ERROR"] == "off"


def test_op_needs_valid_outputs() -> None:
    """§9.2 SO: "Il master invia Output validi" before OP; without process data 0x0019."""
    bench = Bench(sync_mode="free_run")
    bench.to_state(AlState.SAFEOP)
    bench.frames = False
    bench.run(0.2)
    bench.request(AlState.OP)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0x0019


@pytest.mark.parametrize("state", [AlState.SAFEOP, AlState.OP])
def test_injected_config_error_shows_as_a_refused_configuration(state: AlState) -> None:
    """§9.3.7 0xA000 injected while the device is in SAFE-OP / OP: it shows what a TRS-CAT
    with a configuration error shows (§9.2 PS check, §8.1 / ETG.1300): back in PRE-OP, AL
    status 0x12 with code 0x0070, ERROR LED blinking ("invalid configuration"), outputs in
    the safe state; SAFE-OP stays refused until the fault is cleared."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.to_state(state)
    bench.apply("set_output", channel=1, value=1)
    bench.run(0.005)
    bench.apply("inject_fault", fault="CONFIG_ERROR")
    bench.run(0.005)
    trs = bench.trs
    assert (trs.al_state, trs.al_status, trs.al_status_code) == (AlState.PREOP, 0x12, 0x0070)
    assert bench.leds()["ERROR"] == "blinking"
    assert bench.leds()["I/O 1"] == "off"
    bench.request(AlState.SAFEOP)
    assert (trs.al_state, trs.al_status_code) == (AlState.PREOP, 0x0070)
    assert bench.leds()["ERROR"] == "blinking"
    bench.apply("clear_fault", fault="CONFIG_ERROR")
    bench.request(AlState.SAFEOP)
    assert trs.al_state is AlState.SAFEOP and bench.leds()["ERROR"] == "off"


def test_injected_config_error_under_the_master() -> None:
    """The built-in master sees the fall and retries: every retry is refused with 0x0070 and
    the ERROR LED keeps blinking; cleared, the master brings the device back to OP."""
    bench = Bench(["IO-E"], configured=["IO-E"], master=True)
    bench.run(1.0)
    assert bench.trs.al_state is AlState.OP
    bench.apply("inject_fault", fault="CONFIG_ERROR")
    patterns = set()
    for _ in range(3000):
        bench.step()
        patterns.add(bench.leds()["ERROR"])
    assert bench.trs.al_state is AlState.PREOP and bench.trs.al_status_code == 0x0070
    assert bench.leds()["ERROR"] == "blinking" and "blinking" in patterns
    bench.apply("clear_fault", fault="CONFIG_ERROR")
    bench.run(5.0)
    assert bench.trs.al_state is AlState.OP
