"""The drive's EtherCAT state machine: checks per transition as data, AL status, error kinds.

Seed 004 ch. 5 "Stati macchina": INIT (no mailbox), PREOP (mailbox, no process data), SAFEOP
(mailbox, inputs only), OP (both); "BOOT ... Nota: non presente nel drive"; a change happens
"solo nel caso in cui la configurazione richiesta sia valida", and configuration errors are
"Error Init / Error PreOp / Error SafeOp". Allowed requests are the ETG.1000.6 ones
(devices.ethercat.ALLOWED_TRANSITIONS); the AL status codes are those of seed 000 §7.7.

The events carry the drive's device id (the slave is the drive's EtherCAT side, as the CANopen
node is its CAN side): ESM moves are ``state`` events with ``machine: "esm"``, because the
drive's main state machine is CiA 402.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from devices.ethercat import AL_STATUS_ERROR_FLAG, ALLOWED_TRANSITIONS, AlState
from devices.events import AlStatusChanged, Event, StateChanged

MACHINE = "esm"

NO_ERROR = 0x0000
INVALID_STATE_CHANGE = 0x0011  # a request outside ALLOWED_TRANSITIONS
BOOTSTRAP_NOT_SUPPORTED = 0x0013  # ch. 5: BOOT "non presente nel drive"
NO_VALID_OUTPUTS = 0x0019  # SAFEOP -> OP without process data from the master
SM_WATCHDOG = 0x001B  # OP: no process data for the SM watchdog time
INVALID_INPUT_MAPPING = 0x0024  # PREOP -> SAFEOP: a TxPDO assignment that cannot work
INVALID_OUTPUT_MAPPING = 0x0025  # PREOP -> SAFEOP: an RxPDO assignment that cannot work

# Ch. 5 "Transizioni": what the slave verifies before it acknowledges a step up, in order (the
# names are methods of the slave returning None or the refusing AL status code). I -> P has
# nothing the drive can refuse: the master only sets up the mailbox sync managers.
TRANSITION_CHECKS: dict[tuple[AlState, AlState], tuple[str, ...]] = {
    (AlState.INIT, AlState.PREOP): (),
    (AlState.PREOP, AlState.SAFEOP): ("check_output_mapping", "check_input_mapping"),
    (AlState.SAFEOP, AlState.OP): ("check_outputs",),
}

RANK: dict[AlState, int] = {AlState.INIT: 0, AlState.PREOP: 1, AlState.SAFEOP: 2,
                            AlState.OP: 3}


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; it picks the Error LED pattern (ETG.1300)."""

    NONE = "none"
    REFUSED = "refused"  # a requested transition refused (invalid configuration)
    LOCAL = "local"  # the slave left its state on its own
    WATCHDOG = "watchdog"  # ... because the process data stopped (SM watchdog)


def request_refusal(current: AlState, target: AlState) -> int | None:
    """The AL status code of a request the ESM table forbids, or None when it is allowed."""
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

    def at_least(self, state: AlState) -> bool:
        return RANK[self.state] >= RANK[state]

    def accept(self, target: AlState, t_us: int) -> None:
        """A requested transition done: the error flag is acknowledged, the code cleared."""
        self.requested = target
        self.error = ErrorKind.NONE
        self._set_code(NO_ERROR, t_us)
        self._move(target, t_us)

    def refuse(self, code: int, t_us: int) -> None:
        """A requested transition refused: stay, raise the error flag, say why."""
        self.error = ErrorKind.REFUSED
        self._set_code(code, t_us)

    def fall(self, target: AlState, code: int, kind: ErrorKind, t_us: int) -> None:
        """Leave the state on the slave's own initiative: error flag + code."""
        self.error = kind
        self._set_code(code, t_us)
        self._move(target, t_us)

    def reset(self, t_us: int) -> None:
        """The ESC lost its supply (the drive was switched off): INIT, no error."""
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
                                   to_state=target.label, machine=MACHINE))
