"""The CPX-E-EC's EtherCAT state machine as the master sees it: AL status and its code.

The state holder and the ESM's own rules; which checks a transition runs (bootloader, sync
managers, module idents) is decided in devices/cpx/device.py. Codes are the AL status codes of
devices/ethercat.py (seed 000 §7.7, ETG.1000.6). Unlike the FastCAT, the CPX-E-EC has a BOOT
state (Tab. 11: "Bootstrap: the bus module receives a firmware update"), reached from INIT.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import ClassVar

from devices import esm, sync_managers
from devices.cpx.leds import ErrorShows
from devices.ethercat import ALLOWED_TRANSITIONS, AlState

NO_ERROR = esm.NO_ERROR
INVALID_STATE_CHANGE = esm.INVALID_STATE_CHANGE
NO_VALID_FIRMWARE = 0x0014  # bootloader mode or a booting error: no application runs
INVALID_MAILBOX_PREOP = sync_managers.INVALID_MAILBOX_PREOP  # SM0 / SM1 at INIT -> PREOP
SYNC_ERROR = 0x001A  # Tab. 12 single flash: OP -> SAFEOP because of a sync error
SM_WATCHDOG = 0x001B  # Tab. 12 double flash: Sync Manager watchdog
INVALID_OUTPUT_CONFIG = sync_managers.INVALID_OUTPUT_CONFIG  # SM2, > 64 bytes (§2.2)
INVALID_INPUT_CONFIG = sync_managers.INVALID_INPUT_CONFIG  # SM3, > 64 bytes
INVALID_INPUT_MAPPING = 0x0024  # 0x1C13 left at sub 0 = 0 (devices/cpx/assignment.py)
IDENT_MISMATCH = 0x0070  # 0xF030 and 0xF050 differ (Tab. 17 Text-ID 0x3800)
# ETG.1000.6 AL control / AL status bit 5 (ETG.1020 Explicit Device Identification): the
# master's "ID request" and the slave's "ID loaded", the ID then in the AL status code.
AL_CONTROL_ID_REQUEST = 0x0020
AL_STATUS_ID_LOADED = 0x0020

TRANSITIONS: frozenset[tuple[AlState, AlState]] = ALLOWED_TRANSITIONS | {
    (AlState.INIT, AlState.BOOT), (AlState.BOOT, AlState.INIT)}


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; each has its Error LED pattern (Tab. 12)."""

    NONE = "none"
    REFUSED = "refused"  # a requested transition refused: invalid configuration
    WATCHDOG = "watchdog"  # OP -> SAFEOP, Sync Manager watchdog
    SYNC = "sync"  # OP -> SAFEOP, sync error
    # INIT + error from the start: the application controller's flash failed its checksum
    # (Tab. 12 flickering, ETG.1300 "booting error": INIT reached, the error bit set)
    BOOTING = "booting"


ERROR_LED: dict[ErrorKind, ErrorShows] = {
    ErrorKind.NONE: ErrorShows.NONE,
    ErrorKind.REFUSED: ErrorShows.INVALID_CONFIGURATION,
    ErrorKind.WATCHDOG: ErrorShows.WATCHDOG,
    ErrorKind.SYNC: ErrorShows.SYNC_ERROR,
    ErrorKind.BOOTING: ErrorShows.BOOTING_ERROR,
}


def request_refusal(current: AlState, target: AlState) -> int | None:
    """The AL status code for a request the transition table forbids, else None."""
    return esm.request_refusal(current, target, TRANSITIONS, has_boot=True)


@dataclass(slots=True)  # as devices/esm.py's
class Esm(esm.Esm[ErrorKind]):
    error: ErrorKind = ErrorKind.NONE
    kinds: ClassVar[type[ErrorKind]] = ErrorKind

    def fall(self, target: AlState, kind: ErrorKind, code: int, t_us: int) -> None:
        """Leave the state on the slave's own initiative (watchdog, sync error)."""
        self.fall_to(target, kind, code, t_us)
