"""The CPX-E-EC's EtherCAT state machine as the master sees it: AL status and its code.

The state holder and the ESM's own rules; which checks a transition runs (bootloader, sync
managers, module idents) is decided in devices/cpx/device.py. Codes are the AL status codes of
devices/ethercat.py (seed 000 §7.7, ETG.1000.6). Unlike the FastCAT, the CPX-E-EC has a BOOT
state (Tab. 11: "Bootstrap: the bus module receives a firmware update"), reached from INIT.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from devices.cpx.leds import ErrorShows
from devices.ethercat import AL_STATUS_ERROR_FLAG, ALLOWED_TRANSITIONS, AlState
from devices.events import AlStatusChanged, Event, StateChanged

NO_ERROR = 0x0000
INVALID_STATE_CHANGE = 0x0011
NO_VALID_FIRMWARE = 0x0014  # bootloader mode or a booting error: no application runs
INVALID_MAILBOX_PREOP = 0x0016  # SM0 / SM1 refused at INIT -> PREOP
INVALID_SM_CONFIG = 0x0017
SYNC_ERROR = 0x001A  # Tab. 12 single flash: OP -> SAFEOP because of a sync error
SM_WATCHDOG = 0x001B  # Tab. 12 double flash: Sync Manager watchdog
INVALID_OUTPUT_CONFIG = 0x001D  # SM2 size
INVALID_INPUT_CONFIG = 0x001E  # SM3 size
IDENT_MISMATCH = 0x0070  # 0xF030 and 0xF050 differ (Tab. 17 Text-ID 0x3800)

TRANSITIONS: frozenset[tuple[AlState, AlState]] = ALLOWED_TRANSITIONS | {
    (AlState.INIT, AlState.BOOT), (AlState.BOOT, AlState.INIT)}


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; each has its Error LED pattern (Tab. 12)."""

    NONE = "none"
    REFUSED = "refused"  # a requested transition refused: invalid configuration
    WATCHDOG = "watchdog"  # OP -> SAFEOP, Sync Manager watchdog
    SYNC = "sync"  # OP -> SAFEOP, sync error


ERROR_LED: dict[ErrorKind, ErrorShows] = {
    ErrorKind.NONE: ErrorShows.NONE,
    ErrorKind.REFUSED: ErrorShows.INVALID_CONFIGURATION,
    ErrorKind.WATCHDOG: ErrorShows.WATCHDOG,
    ErrorKind.SYNC: ErrorShows.SYNC_ERROR,
}


def request_refusal(current: AlState, target: AlState) -> int | None:
    """The AL status code for a request the transition table forbids, else None."""
    if target is current or (current, target) in TRANSITIONS:
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
        """AL status (0x0130): the state, plus 0x10 while the error flag is set."""
        flag = AL_STATUS_ERROR_FLAG if self.error is not ErrorKind.NONE else 0
        return int(self.state) | flag

    def accept(self, target: AlState, t_us: int) -> None:
        self.requested = target
        self.error = ErrorKind.NONE
        self._set_code(NO_ERROR, t_us)
        self._move(target, t_us)

    def refuse(self, code: int, t_us: int, kind: ErrorKind = ErrorKind.REFUSED) -> None:
        """Stay, raise the error flag; ``kind`` says which Error LED pattern tells why."""
        self.error = kind
        self._set_code(code, t_us)

    def fall(self, target: AlState, kind: ErrorKind, code: int, t_us: int) -> None:
        """Leave the state on the slave's own initiative (watchdog, sync error)."""
        self.error = kind
        self._set_code(code, t_us)
        self._move(target, t_us)

    def reset(self, t_us: int) -> None:
        """INIT without an error (power-up, restart of the application controller)."""
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
