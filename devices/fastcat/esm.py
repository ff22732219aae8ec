"""The coupler's EtherCAT state machine as the master sees it: AL status and AL status code.

The coupler's error kinds on the shared state holder (devices/esm.py); what the coupler allows
(scan in progress, latched alarm, address check) is decided in devices/fastcat/coupler.py.
Requests outside the ETG.1000.6 transition table (devices.ethercat.ALLOWED_TRANSITIONS) answer
the §7.7 codes below.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import ClassVar

from devices import esm
from devices.ethercat import AlState

# §7.7 codes for requests the ESM itself refuses (the shared ones of devices/esm.py).
INVALID_STATE_CHANGE = esm.INVALID_STATE_CHANGE  # "Invalid requested state change"
BOOTSTRAP_NOT_SUPPORTED = esm.BOOTSTRAP_NOT_SUPPORTED  # the FastCAT has no BOOT state
NO_ERROR = esm.NO_ERROR
# §7.7 "Sync manager watchdog": no process data (SM2) for the watchdog time, in OP it drops the
# coupler to SAFEOP, and SAFEOP -> OP without process data in that time is refused (the ESI's
# SM2 control 0x64 has the watchdog trigger on; SSC firmware, docs/fastcat-coupler.md).
SM_WATCHDOG = 0x001B
SM_WATCHDOG_US = 100_000  # ESC default: 0x0420 = 1000 x 100 us (the 0x0400 divider)

# INIT -> BOOT: 0x0013 (no BOOT state); BOOT from PREOP / SAFEOP / OP and any other request
# outside ALLOWED_TRANSITIONS: 0x0011 (ETG.1000.6, the shared rule).
request_refusal = esm.request_refusal


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; drives the ERR LED (ETG.1300)."""

    NONE = "none"
    REFUSED = "refused"  # a requested transition was refused: ERR blinking
    AUTONOMOUS = "autonomous"  # the slave left OP/SAFEOP on its own: ERR single flash
    WATCHDOG = "watchdog"  # the SM watchdog (0x001B), a fall or a refusal: ERR double flash


@dataclass(slots=True)  # as devices/esm.py's
class Esm(esm.Esm[ErrorKind]):
    error: ErrorKind = ErrorKind.NONE
    kinds: ClassVar[type[ErrorKind]] = ErrorKind

    def fall(self, target: AlState, code: int, t_us: int) -> None:
        """Leave the state on the slave's own initiative (an alarm): error flag + code."""
        self.fall_to(target, ErrorKind.AUTONOMOUS, code, t_us)

    def drop_to_init(self, t_us: int) -> None:
        """Back to INIT without an error (power loss, CNF procedure)."""
        self.reset(t_us)
