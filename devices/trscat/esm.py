"""The TRS-CAT EtherCAT state machine: transition checks as data, AL status, error kinds.

Seed 001 §9.2 (what is checked on each transition), devices.ethercat (ETG.1000.6 transitions
and the AL status code table, seed 000 §7.7). The checks themselves are methods of the device
named in :data:`TRANSITION_CHECKS`; each returns None or the AL status code that refuses.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from devices.ethercat import AL_STATUS_ERROR_FLAG, ALLOWED_TRANSITIONS, AlState
from devices.events import AlStatusChanged, Event, StateChanged

NO_ERROR = 0x0000
UNSPECIFIED_ERROR = 0x0001  # deadlock after 0x6100 (the seed names no AL status code)
INVALID_STATE_CHANGE = 0x0011
BOOTSTRAP_NOT_SUPPORTED = 0x0013  # §9.2 has no BOOT state
NO_VALID_OUTPUTS = 0x0019
SYNC_ERROR = 0x001A  # SM events missed up to 0x10F1:2
SM_WATCHDOG = 0x001B
FATAL_SYNC_ERROR = 0x002C  # SYNC0 lost
CYCLE_TOO_SMALL = 0x002E  # SYNC0 cycle below 0x1C32:5 (500 us)
INVALID_DC_SYNC = 0x0030
MODULE_IDENT_MISMATCH = 0x0070  # 0xF030 != 0xF050 at PS (§9.2; code of seed 000 §7.7)

# §9.2: what the device verifies on each transition, in this order (device methods).
# INIT -> PREOP has no check that refuses: it waits for the power-up detection (§9.2 INIT).
TRANSITION_CHECKS: dict[tuple[AlState, AlState], tuple[str, ...]] = {
    (AlState.INIT, AlState.PREOP): (),
    (AlState.PREOP, AlState.SAFEOP): ("check_not_deadlocked", "check_dc", "check_idents"),
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
}


def request_refusal(current: AlState, target: AlState) -> int | None:
    """The AL status code for a request the ESM table forbids, or None when it is allowed."""
    if target is AlState.BOOT:
        return BOOTSTRAP_NOT_SUPPORTED
    if target is current or (current, target) in ALLOWED_TRANSITIONS:
        return None
    return INVALID_STATE_CHANGE


@dataclass
class Esm:
    emit: Callable[[Event], None]
    device: str
    state: AlState = AlState.INIT
    requested: AlState = AlState.INIT
    error: ErrorKind = ErrorKind.NONE
    code: int = NO_ERROR

    @property
    def register(self) -> int:
        """AL status register 0x0130: the state, + 0x10 while the error flag is set."""
        flag = AL_STATUS_ERROR_FLAG if self.error is not ErrorKind.NONE else 0
        return int(self.state) | flag

    def accept(self, target: AlState, t_us: int) -> None:
        self.requested = target
        self.error = ErrorKind.NONE
        self._set_code(NO_ERROR, t_us)
        self._move(target, t_us)

    def refuse(self, code: int, t_us: int) -> None:
        self.error = ErrorKind.REFUSED
        self._set_code(code, t_us)

    def fall(self, target: AlState, code: int, t_us: int) -> None:
        """Leave the state on the device's own initiative: error flag + code."""
        self.error = FALL_KIND.get(code, ErrorKind.LOCAL)
        self._set_code(code, t_us)
        self._move(target, t_us)

    def reset(self, t_us: int) -> None:
        """Power off: INIT, no error."""
        self.requested = AlState.INIT
        self.error = ErrorKind.NONE
        self._set_code(NO_ERROR, t_us)
        self._move(AlState.INIT, t_us)

    def _set_code(self, code: int, t_us: int) -> None:
        if code != self.code:
            self.code = code
            self.emit(AlStatusChanged(t_us, self.device, code=code))

    def _move(self, target: AlState, t_us: int) -> None:
        if target is not self.state:
            before, self.state = self.state, target
            self.emit(StateChanged(t_us, self.device, from_state=before.label,
                                   to_state=target.label))
