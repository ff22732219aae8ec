"""The coupler's EtherCAT state machine as the master sees it: AL status and AL status code.

The state holder only; what the coupler allows (scan in progress, latched alarm, address check)
is decided in devices/fastcat/coupler.py. Requests outside the ETG.1000.6 transition table
(devices.ethercat.ALLOWED_TRANSITIONS) answer the §7.7 codes below.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from devices.ethercat import AL_STATUS_ERROR_FLAG, ALLOWED_TRANSITIONS, AlState
from devices.events import AlStatusChanged, Event, StateChanged

# §7.7 codes for requests the ESM itself refuses.
INVALID_STATE_CHANGE = 0x0011  # "Invalid requested state change"
BOOTSTRAP_NOT_SUPPORTED = 0x0013  # "Bootstrap not supported" (the FastCAT has no BOOT state)
NO_ERROR = 0x0000


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; drives the ERR LED (ETG.1300)."""

    NONE = "none"
    REFUSED = "refused"  # a requested transition was refused: ERR blinking
    AUTONOMOUS = "autonomous"  # the slave left OP/SAFEOP on its own: ERR single flash


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
    def error_flag(self) -> bool:
        return self.error is not ErrorKind.NONE

    @property
    def register(self) -> int:
        """AL status register 0x0130: the state, plus 0x10 while the error flag is set."""
        return int(self.state) | (AL_STATUS_ERROR_FLAG if self.error_flag else 0)

    def accept(self, target: AlState, t_us: int) -> None:
        """A requested transition done: the error flag is acknowledged, the code cleared."""
        self.requested = target
        self.error = ErrorKind.NONE
        self._set_code(NO_ERROR, t_us)
        self._move(target, t_us)

    def refuse(self, code: int, t_us: int) -> None:
        """A requested transition refused: stay, raise the error flag, report why."""
        self.error = ErrorKind.REFUSED
        self._set_code(code, t_us)

    def fall(self, target: AlState, code: int, t_us: int) -> None:
        """Leave the state on the slave's own initiative (an alarm): error flag + code."""
        self.error = ErrorKind.AUTONOMOUS
        self._set_code(code, t_us)
        self._move(target, t_us)

    def drop_to_init(self, t_us: int) -> None:
        """Back to INIT without an error (power loss, CNF procedure)."""
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
