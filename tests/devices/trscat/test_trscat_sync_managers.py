"""Seed 001 §9.2: the TRS-CAT checks the mailbox initialisation at INIT -> PREOP (l. 477-478)
and the process-data sync managers at PREOP -> SAFEOP (l. 501-502), before the DC and the
0xF030 = 0xF050 checks; from the registers a master on the wire wrote, or from a fault
injected for the built-in master."""

from __future__ import annotations

from dataclasses import replace

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.sync_managers import SmSetup
from devices.trscat.sync import SYNC0_ACTIVE

# The ESI layout with the integrated module only: SM2 = 16 outputs (2 bytes), SM3 = 16
# inputs + 0x1AFF (8 + 4 bits) = 28 bits (4 bytes).
GOOD = (SmSetup(0x1000, 128, 0x26, True), SmSetup(0x1080, 128, 0x22, True),
        SmSetup(0x1100, 2, 0x64, True), SmSetup(0x1400, 4, 0x20, True))


def _with(sm: int, **changes: object) -> tuple[SmSetup, ...]:
    setups = list(GOOD)
    setups[sm] = replace(setups[sm], **changes)  # type: ignore[arg-type]
    return tuple(setups)


def _answered(bench: Bench, current: AlState, target: AlState, code: int | None) -> None:
    """Accepted (``code`` None), or refused with ``code``: blinking ERROR, a 0x10F3 message."""
    trs = bench.trs
    if code is None:
        assert (trs.al_state, trs.al_status_code) == (target, 0)
        return
    assert (trs.al_state, trs.al_status_code) == (current, code)
    assert bench.leds()["ERROR"] == "blinking"
    assert any(m["diag_code"] == f"0x{0xE0000000 | code:08X}" for m in bench.messages())


@pytest.mark.parametrize(("setups", "code"), [
    (GOOD, None),
    (_with(0, start=0x1800), 0x0016),
    (_with(1, length=64), 0x0016),
    (_with(0, control=0x22), 0x0016),  # SM0 set up as the master's read mailbox
    (_with(1, enabled=False), 0x0016),
])
def test_mailbox_setup_is_checked_at_init_to_preop(setups, code) -> None:
    bench = Bench()
    bench.settle()
    bench.trs.configure_sync_managers(setups)
    bench.request(AlState.PREOP)
    _answered(bench, AlState.INIT, AlState.PREOP, code)


def test_a_bad_mailbox_refuses_preop_after_the_detection_too() -> None:
    """A PREOP request made during the power-up detection is answered when it ends."""
    bench = Bench()
    bench.trs.configure_sync_managers(_with(0, start=0x1800))
    bench.request(AlState.PREOP)
    bench.settle()
    assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.INIT, 0x0016)


@pytest.mark.parametrize(("setups", "code"), [
    (GOOD, None),
    (_with(2, length=3), 0x001D),
    (_with(2, enabled=False), 0x001D),
    (_with(3, length=2), 0x001E),
    # The wrong direction / mode: the SM's own code as the ETG sample stack's CheckSmSettings
    # gives every SM2 / SM3 fault (0x001D / 0x001E), not 0x0017
    (_with(2, control=0x20), 0x001D),  # SM2 set up for the master to read
    (_with(2, control=0x66), 0x001D),  # SM2 as a mailbox (1-buffer)
    (_with(3, control=0x24), 0x001E),  # SM3 set up for the master to write
    (_with(3, start=0x1800), None),  # where the process data sit is the master's choice
])
def test_process_data_setup_is_checked_at_preop_to_safeop(setups, code) -> None:
    bench = Bench()
    bench.settle()
    bench.trs.configure_sync_managers(GOOD)
    bench.request(AlState.PREOP)
    bench.trs.configure_sync_managers(setups)
    bench.request(AlState.SAFEOP)
    _answered(bench, AlState.PREOP, AlState.SAFEOP, code)


def test_sm2_size_follows_the_configured_slots() -> None:
    """0xF030 with a TRS-IO-E: two more bytes each way (16 outputs, 16 inputs)."""
    bench = Bench(["IO-E"], configured=["IO-E"])
    bench.settle()
    bench.trs.configure_sync_managers(GOOD)
    bench.request(AlState.PREOP)
    bench.trs.configure_sync_managers((*_with(2, length=4)[:3], replace(GOOD[3], length=6)))
    bench.request(AlState.SAFEOP)
    assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.SAFEOP, 0)


def test_sm_is_checked_before_dc_and_idents() -> None:
    """A field engineer fixes the SM layout first: with a bad SYNC0 cycle and a wrong 0xF030
    too, the refusal names the sync manager."""
    bench = Bench(["IO-E"], dc=False)
    bench.settle()
    bench.trs.configure_sync_managers(GOOD)
    bench.request(AlState.PREOP)
    bench.write(0xF030, 0, 1)  # the expansion left out: 0x0070 at PS
    bench.configure_dc(SYNC0_ACTIVE, 400_000)  # below 500 us: 0x002E at PS
    bench.trs.configure_sync_managers(_with(3, length=5))
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_status_code == 0x001E
    bench.trs.configure_sync_managers(GOOD)
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_status_code == 0x002E


@pytest.mark.parametrize(("fault", "sm", "state", "code"), [
    ("sm_invalid_address", 0, AlState.INIT, 0x0016),
    ("sm_invalid_settings", 1, AlState.INIT, 0x0016),
    ("sm_invalid_size", 2, AlState.PREOP, 0x001D),
    ("sm_invalid_size", 3, AlState.PREOP, 0x001E),
    ("sm_invalid_settings", 2, AlState.PREOP, 0x001D),
    ("sm_invalid_address", 3, AlState.PREOP, 0x001E),
])
def test_injected_sm_faults_with_the_built_in_master(fault, sm, state, code) -> None:
    bench = Bench(master=True)
    bench.apply("inject_sm_fault", fault=fault, sm=sm)
    bench.run(1.0)
    assert (bench.trs.al_state, bench.trs.al_status_code) == (state, code)
    assert {"fault": fault, "sm": sm} in bench.trs.snapshot()["injected_sm"]
    bench.apply("clear_sm_fault", fault=fault, sm=sm)
    bench.run_until(lambda: bench.trs.al_state is AlState.OP)
