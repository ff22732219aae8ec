"""The TRS-CAT EtherCAT state machine: transition checks as data, AL status, error kinds.

Seed 001 §9.2 (what is checked on each transition), devices.ethercat (ETG.1000.6 transitions
and the AL status code table, seed 000 §7.7). The checks themselves are methods of the device
named in :data:`TRANSITION_CHECKS`; each returns None or the AL status code that refuses.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import ClassVar

from devices import esm
from devices.ethercat import AlState

NO_ERROR = esm.NO_ERROR
UNSPECIFIED_ERROR = 0x0001  # deadlock after 0x6100 (the seed names no AL status code)
INVALID_STATE_CHANGE = esm.INVALID_STATE_CHANGE
BOOTSTRAP_NOT_SUPPORTED = esm.BOOTSTRAP_NOT_SUPPORTED  # §9.2 has no BOOT state
NO_VALID_OUTPUTS = 0x0019
SYNC_ERROR = 0x001A  # SM events missed up to 0x10F1:2
SM_WATCHDOG = 0x001B
FATAL_SYNC_ERROR = 0x002C  # SYNC0 lost
CYCLE_TOO_SMALL = 0x002E  # SYNC0 cycle below 0x1C32:5 (500 us)
INVALID_DC_SYNC = 0x0030
# devices/sync_managers.py: 0x0016 (SM0 / SM1), 0x001D (SM2), 0x001E (SM3)
MODULE_IDENT_MISMATCH = 0x0070  # 0xF030 != 0xF050 at PS (§9.2; code of seed 000 §7.7)

# §9.2: what the device verifies on each transition, in this order (device methods).
# INIT -> PREOP also waits for the power-up detection (§9.2 INIT). At PS the order is a field
# engineer's: nothing runs deadlocked; then the sync managers (without them no frame reaches
# the device), the DC (when the frames are taken), the modules (0xF030 = 0xF050).
TRANSITION_CHECKS: dict[tuple[AlState, AlState], tuple[str, ...]] = {
    (AlState.INIT, AlState.PREOP): ("check_mailbox",),
    (AlState.PREOP, AlState.SAFEOP): ("check_not_deadlocked", "check_sync_managers",
                                      "check_dc", "check_idents"),
    (AlState.SAFEOP, AlState.OP): ("check_sync", "check_outputs"),
}


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; drives the ERROR LED (ETG.1300)."""

    NONE = "none"
    REFUSED = "refused"  # invalid configuration: a request refused -> blinking
    LOCAL = "local"  # the device left OP on its own (sync error) -> single flash
    WATCHDOG = "watchdog"  # process-data watchdog -> double flash
    APPLICATION = "application"  # 0x6100 internal software error, deadlock -> on


# The kind of autonomous fall each AL status code stands for.
FALL_KIND: dict[int, ErrorKind] = {
    SYNC_ERROR: ErrorKind.LOCAL,
    FATAL_SYNC_ERROR: ErrorKind.LOCAL,
    SM_WATCHDOG: ErrorKind.WATCHDOG,
    UNSPECIFIED_ERROR: ErrorKind.APPLICATION,
    # An injected 0xA000 in SAFE-OP / OP: the device is where a refused PS leaves it, and
    # ETG.1300 shows a configuration error as blinking ("invalid configuration").
    MODULE_IDENT_MISMATCH: ErrorKind.REFUSED,
}


# No BOOT (§9.2): INIT -> BOOT 0x0013; BOOT from PREOP / SAFEOP / OP and any other
# request outside the table: 0x0011 (ETG.1000.6, the shared rule).
request_refusal = esm.request_refusal


@dataclass(slots=True)  # as devices/esm.py's
class Esm(esm.Esm[ErrorKind]):
    error: ErrorKind = ErrorKind.NONE
    kinds: ClassVar[type[ErrorKind]] = ErrorKind

    def fall(self, target: AlState, code: int, t_us: int) -> None:
        """Leave the state on the device's own initiative: error flag + code."""
        self.fall_to(target, FALL_KIND.get(code, ErrorKind.LOCAL), code, t_us)
