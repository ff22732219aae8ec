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
from dataclasses import dataclass
from typing import ClassVar

from devices import esm
from devices.ethercat import AlState

MACHINE = "esm"

NO_ERROR = esm.NO_ERROR
INVALID_STATE_CHANGE = esm.INVALID_STATE_CHANGE  # a request outside ALLOWED_TRANSITIONS
BOOTSTRAP_NOT_SUPPORTED = esm.BOOTSTRAP_NOT_SUPPORTED  # ch. 5: BOOT "non presente nel drive"
NO_VALID_OUTPUTS = 0x0019  # SAFEOP -> OP without process data from the master
SM_WATCHDOG = 0x001B  # OP: no process data for the SM watchdog time
INVALID_INPUT_MAPPING = 0x0024  # PREOP -> SAFEOP: a TxPDO assignment that cannot work
INVALID_OUTPUT_MAPPING = 0x0025  # PREOP -> SAFEOP: an RxPDO assignment that cannot work
NO_VALID_INPUTS_AND_OUTPUTS = 0x002B  # ETG.1000.6: O, S -> PREOP + error; P -> S refused
EEPROM_ERROR = 0x0051  # ETG.1000.6 "EEPROM Error": any -> INIT + error; I -> P refused

# Ch. 5 "Codici allarmi specifici": the drive alarms that take the process data away. 7
# "Processore DSP in fault" is the controller that makes them (statusword, positions, the
# set-points' consumer); 30-32 are the link between it and the EtherCAT interface ("Timeout /
# Errore 1 / Errore 2 comunicazione interna al drive"). The interface itself still runs: its
# mailbox carries their 0x603F codes and emergencies and the reset "via coe" (ch. 5 "Reset
# allarmi"), so the slave leaves SAFEOP / OP for PREOP with 0x002B and stays there until the
# alarm is reset (docs/ethercat-coe.md "Drive alarms and the EtherCAT side").
CONTROLLER_ALARMS: frozenset[int] = frozenset({7, 30, 31, 32})
# Ch. 5: 35 "Errore caricamento eeprom ethercat". ETG.1300 has one ERR row for it, flickering
# "booting error: INIT reached, error indicator bit set": the slave is in INIT + error with
# 0x0051 and refuses PREOP while the alarm is latched (docs/ethercat-coe.md §LEDs).
EEPROM_ALARM = 35

# Ch. 5 "Transizioni": what the slave verifies before it acknowledges a step up, in order (the
# names are methods of the slave returning None or the refusing AL status code). I -> P: the
# EtherCAT EEPROM (alarm 35), then the mailbox sync managers the master set up (0x0016). P -> S:
# the PDO mapping (0x0025 / 0x0024), then the sync managers of the process data
# (0x001D / 0x001E), the ETG sample stack's order (the mapping gives the SM lengths);
# devices/coe/sm_checks.py. S -> O: an injected alarm 34 still standing (0x001B), then the
# master's process data (0x0019).
TRANSITION_CHECKS: dict[tuple[AlState, AlState], tuple[str, ...]] = {
    (AlState.INIT, AlState.PREOP): ("check_eeprom", "check_mailbox"),
    (AlState.PREOP, AlState.SAFEOP): ("check_controller", "check_output_mapping",
                                      "check_input_mapping", "check_sync_managers"),
    (AlState.SAFEOP, AlState.OP): ("check_controller", "check_sync", "check_outputs"),
}

RANK = esm.RANK


class ErrorKind(enum.Enum):
    """Why the AL status error flag is set; it picks the Error LED pattern (ETG.1300)."""

    NONE = "none"
    REFUSED = "refused"  # a requested transition refused (invalid configuration)
    LOCAL = "local"  # the slave left its state on its own
    WATCHDOG = "watchdog"  # ... because the process data stopped (SM watchdog)
    BOOTING = "booting"  # in INIT with an EEPROM that did not load (alarm 35)


# A refusal whose code is not an invalid configuration keeps its own ERR row (ETG.1300): an
# injected alarm 34 refuses SAFEOP -> OP with the SM watchdog's code, and ERR double flashes.
REFUSAL_KIND: dict[int, ErrorKind] = {EEPROM_ERROR: ErrorKind.BOOTING,
                                      SM_WATCHDOG: ErrorKind.WATCHDOG}


def controller_alarm(latched: list[int]) -> int | None:
    """The first latched alarm of CONTROLLER_ALARMS, None when there is none (the usual case,
    asked every step: an empty list answers at once)."""
    for code in latched:
        if code in CONTROLLER_ALARMS:
            return code
    return None


# Ch. 5, no BOOT: INIT -> BOOT 0x0013; BOOT from PREOP / SAFEOP / OP and any other
# request outside the table: 0x0011 (ETG.1000.6, the shared rule).
request_refusal = esm.request_refusal


@dataclass(slots=True)  # as devices/esm.py's
class Esm(esm.Esm[ErrorKind]):
    error: ErrorKind = ErrorKind.NONE
    kinds: ClassVar[type[ErrorKind]] = ErrorKind
    machine: ClassVar[str] = MACHINE  # ESM moves are ``state`` events with machine "esm"

    def fall(self, target: AlState, code: int, kind: ErrorKind, t_us: int) -> None:
        """Leave the state on the slave's own initiative: error flag + code."""
        self.fall_to(target, kind, code, t_us)
