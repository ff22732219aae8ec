"""The sync managers a slave expects its master to set up, and the AL status code of a bad one.

Every slave of the rig has the same layout (its ESI / SII: SM0 mailbox out, SM1 mailbox in,
SM2 outputs, SM3 inputs). A slave checks the mailbox sync managers at INIT -> PREOP (AL status
code 0x0016) and the process-data ones at PREOP -> SAFEOP: whatever is wrong with SM2 (size,
address, direction / mode) is 0x001D, with SM3 0x001E. That is the ETG sample stack's
CheckSmSettings (each SM2 fault ends in ALSTATUSCODE_INVALIDSMOUTCFG, each SM3 one in
ALSTATUSCODE_INVALIDSMINCFG; 0x0017 "Invalid sync manager configuration" is not used there)
with ETG.1000.6's codes. The check is the device's, on what the master wrote (a master on the
wire) or on a fault injected by name (the built-in master configures the sync managers right).
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

# The ESI layout (app/ethercat_wire/faces/base.py puts it into the SII / ESI): start, length
# and control byte. Control 0x26 / 0x22: mailbox, master writes / reads (PDI interrupt);
# 0x64 / 0x20: 3-buffer, master writes (with the watchdog) / reads.
MAILBOX_OUT, MAILBOX_IN, MAILBOX_SIZE = 0x1000, 0x1080, 128
OUTPUTS_START, INPUTS_START = 0x1100, 0x1400
SM_CONTROL = (0x26, 0x22, 0x64, 0x20)
MAILBOX_SMS = (0, 1)
PROCESS_DATA_SMS = (2, 3)
# Control bits 0..3 (buffer type and direction) decide what the SM is; the interrupt and
# watchdog enables are the master's choice and not checked.
MODE_DIRECTION_MASK = 0x0F

INVALID_MAILBOX_PREOP = 0x0016  # "Invalid mailbox configuration (PreOP state)"
INVALID_OUTPUT_CONFIG = 0x001D  # SM2, any fault
INVALID_INPUT_CONFIG = 0x001E  # SM3, any fault
# The AL status code of a fault on each sync manager: one per SM, whatever the fault.
SM_FAULT_CODE = (INVALID_MAILBOX_PREOP, INVALID_MAILBOX_PREOP, INVALID_OUTPUT_CONFIG,
                 INVALID_INPUT_CONFIG)


class SmFault(enum.Enum):
    """What is wrong with a sync manager; the values are the injectable fault names."""

    ADDRESS = "sm_invalid_address"
    SIZE = "sm_invalid_size"
    SETTINGS = "sm_invalid_settings"


SM_FAULTS: dict[str, SmFault] = {f.value: f for f in SmFault}
# What a refusal names as invalid (the TRS-CAT's diagnosis message, the drive's log line).
SM_FAULT_WORDS: dict[SmFault, str] = {
    SmFault.ADDRESS: "start address", SmFault.SIZE: "length",
    SmFault.SETTINGS: "settings (enable, buffer type, direction)"}


@dataclass(frozen=True)
class SmSetup:
    """One sync manager as the master wrote its registers (0x0800 + 8 n)."""

    start: int
    length: int
    control: int
    enabled: bool


def fault_code(sm: int, fault: SmFault) -> int:
    """The AL status code that refuses the transition for ``fault`` on sync manager ``sm``:
    the SM's own (SM_FAULT_CODE); ``fault`` names what in the device's diagnosis only."""
    return SM_FAULT_CODE[sm]


def setup_fault(sm: int, setup: SmSetup | None, pd_bytes: int = 0) -> SmFault | None:
    """What is wrong with sync manager ``sm`` as written, or None. The mailbox ones must be
    the ESI's (start, length, kind); a process-data one must be as long as the PDOs assigned
    to it (``pd_bytes``; disabled when there are none) and of the right kind. Where the master
    puts the process data is its choice (the ESI start is a default)."""
    if sm in MAILBOX_SMS:
        if setup is None or not setup.enabled or not _kind_ok(sm, setup):
            return SmFault.SETTINGS
        if setup.start != (MAILBOX_OUT, MAILBOX_IN)[sm]:
            return SmFault.ADDRESS
        return SmFault.SIZE if setup.length != MAILBOX_SIZE else None
    used = setup is not None and setup.enabled and setup.length > 0
    if not pd_bytes:
        return SmFault.SIZE if used else None
    if setup is None or not used or setup.length != pd_bytes:
        return SmFault.SIZE
    return None if _kind_ok(sm, setup) else SmFault.SETTINGS


def _kind_ok(sm: int, setup: SmSetup) -> bool:
    return setup.control & MODE_DIRECTION_MASK == SM_CONTROL[sm] & MODE_DIRECTION_MASK


def check_setup(setups: Sequence[SmSetup], sms: Sequence[int],
                pd_bytes: Callable[[int], int]) -> tuple[int, SmFault] | None:
    """The first of ``sms`` the master set up wrong: (SM number, fault), or None.
    ``pd_bytes(sm)`` is the size of the PDOs assigned to a process-data sync manager."""
    for sm in sms:
        setup = setups[sm] if sm < len(setups) else None
        fault = setup_fault(sm, setup, pd_bytes(sm) if sm in PROCESS_DATA_SMS else 0)
        if fault is not None:
            return sm, fault
    return None


def injected_fault(injected: Sequence[tuple[str, int | None]],
                   sms: Sequence[int]) -> tuple[int, SmFault] | None:
    """The first injected sync manager fault (name, SM) on one of ``sms``, or None."""
    for name, sm in injected:
        if name in SM_FAULTS and sm in sms:
            return sm, SM_FAULTS[name]
    return None


Peek = Callable[[int, int], Any]


def assigned_bytes(peek: Peek, assign_index: int) -> int:
    """The bytes of the PDOs an assignment object (0x1C12 / 0x1C13) lists: the bit lengths of
    their mapping entries (ETG.1000.6: index << 16 | sub << 8 | bits), rounded up."""
    bits = 0
    for sub in range(1, int(peek(assign_index, 0)) + 1):
        pdo = int(peek(assign_index, sub))
        bits += sum(int(peek(pdo, e)) & 0xFF
                    for e in range(1, int(peek(pdo, 0)) + 1))
    return (bits + 7) // 8
