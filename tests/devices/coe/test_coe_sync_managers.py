"""The drive checks the sync managers its master set up (seed 004 ch. 5 "Transizioni": "Error
Init / Error PreOp / Error SafeOp: Errori nella configurazione (es sui DC, FMMU, SyncManager
etc ..)"; I -> P "SyncManager per la comunicazione via mailbox"; P -> S "i SyncManager").

The rule is devices/sync_managers.py, the TRS-CAT's and the CPX-E-EC's: SM0 / SM1 as the ESI
says at INIT -> PREOP (0x0016), SM2 / SM3 as long as the PDOs 0x1C12 / 0x1C13 assign at
PREOP -> SAFEOP (0x001D / 0x001E). Only what a master on the wire wrote is checked: the
built-in master sets them up right (no setup known: accepted).
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from coe_bench import Bench, make_bench

from devices.ethercat import AlState
from devices.sync_managers import SmSetup

# The ESI layout with the default assignment: 0x1600 (6 bytes) on SM2, 0x1A02 (6 bytes) on SM3.
GOOD = (SmSetup(0x1000, 128, 0x26, True), SmSetup(0x1080, 128, 0x22, True),
        SmSetup(0x1100, 6, 0x64, True), SmSetup(0x1400, 6, 0x20, True))


def _with(sm: int, **changes: object) -> tuple[SmSetup, ...]:
    setups = list(GOOD)
    setups[sm] = replace(setups[sm], **changes)  # type: ignore[arg-type]
    return tuple(setups)


def _answered(bench: Bench, current: AlState, target: AlState, code: int | None) -> None:
    """Accepted (``code`` None), or refused with ``code`` and the Error LED blinking
    (ETG.1300 invalid configuration)."""
    slave = bench.slave
    if code is None:
        assert (slave.al_state, slave.al_status_code) == (target, 0)
        return
    assert (slave.al_state, slave.al_status & 0x10, slave.al_status_code) == (current, 0x10,
                                                                             code)
    assert bench.drive.snapshot()["leds"]["Error"] == "blinking"


@pytest.mark.parametrize(("setups", "code"), [
    (GOOD, None),
    (_with(0, start=0x1800), 0x0016),
    (_with(1, length=64), 0x0016),
    (_with(0, control=0x22), 0x0016),  # SM0 set up as the master's read mailbox
    (_with(1, enabled=False), 0x0016),
])
def test_mailbox_setup_is_checked_at_init_to_preop(setups, code) -> None:
    bench = make_bench()
    bench.slave.configure_sync_managers(setups)
    bench.go(AlState.PREOP)
    _answered(bench, AlState.INIT, AlState.PREOP, code)


@pytest.mark.parametrize(("setups", "code"), [
    (GOOD, None),
    (_with(2, length=3), 0x001D),
    (_with(2, enabled=False), 0x001D),
    (_with(3, length=4), 0x001E),
    (_with(2, control=0x20), 0x001D),  # SM2 set up for the master to read
    (_with(3, control=0x24), 0x001E),  # SM3 set up for the master to write
    (_with(3, start=0x1800), None),  # where the process data sit is the master's choice
])
def test_process_data_setup_is_checked_at_preop_to_safeop(setups, code) -> None:
    bench = make_bench()
    bench.slave.configure_sync_managers(setups)
    bench.go(AlState.PREOP)
    bench.go(AlState.SAFEOP)
    _answered(bench, AlState.PREOP, AlState.SAFEOP, code)
    assert 33 not in bench.drive.alarms.latched  # the PDO mapping itself is right


def test_a_new_assignment_needs_its_sm2_length() -> None:
    """0x1601 added to 0x1C12 ("si possono ulteriormente mappare gli oggetti 0x1601"): 6 + 3
    bytes of outputs. A master that keeps SM2 at 6 bytes is refused; SM2 at 9 passes."""
    bench = make_bench()
    bench.slave.configure_sync_managers(GOOD)
    bench.go(AlState.PREOP)
    bench.write(0x1C12, 0, 0, 1)
    bench.write(0x1C12, 2, 0x1601, 2)
    bench.write(0x1C12, 0, 2, 1)
    bench.go(AlState.SAFEOP)
    _answered(bench, AlState.PREOP, AlState.SAFEOP, 0x001D)
    bench.slave.configure_sync_managers(_with(2, length=9))
    bench.go(AlState.SAFEOP)
    _answered(bench, AlState.PREOP, AlState.SAFEOP, None)


def test_the_built_in_master_sets_them_up_right() -> None:
    """No SM registers known (the built-in master): nothing to refuse."""
    bench = make_bench()
    bench.up_to(AlState.OP)
