"""The drive's EtherCAT LEDs (seed 004 ch. 5 "Connessioni e Leds Drive EtherCAT").

"L/A verde: Link Active rete ethernet"; "Status verde: segnalazione dello stato ethercat. Se
sempre acceso ethercat è in operational mode ... ETG-1300"; "Error rosso: segnalazione
warning/allarmi in ethercat. La frequenza di lampeggio è funzione della tipologia di allarme
... ETG-1300". Status is the ETG.1300 RUN indicator and L/A its link/activity indicator (the
tables are the TRS-CAT's, which are ETG.1300's). Error is ETG.1300 ERR for the EtherCAT
errors; a drive alarm with no EtherCAT error lights it steadily (docs/ethercat-coe.md §LEDs).
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.coe.esm import ErrorKind
from devices.ethercat import AlState
from devices.leds import LedPattern
from devices.servo.leds import ERROR, LINK, STATUS
from devices.trscat.indicators import RUN_BY_STATE, link_led

__all__ = ["ERROR", "LINK", "STATUS", "LedInputs", "wanted_patterns"]

# ETG.1300 ERR: blinking = invalid configuration, single flash = local error (the slave left
# its state on its own), double flash = process data watchdog timeout.
ERROR_BY_KIND: dict[ErrorKind, LedPattern] = {
    ErrorKind.NONE: LedPattern.OFF,
    ErrorKind.REFUSED: LedPattern.BLINKING,
    ErrorKind.LOCAL: LedPattern.SINGLE_FLASH,
    ErrorKind.WATCHDOG: LedPattern.DOUBLE_FLASH,
}
DRIVE_ALARM = LedPattern.ON


@dataclass(frozen=True)
class LedInputs:
    on_line: bool  # powered, c9 = EtherCAT at power-up
    link: bool
    activity: bool
    state: AlState
    error: ErrorKind
    drive_alarm: bool


def wanted_patterns(s: LedInputs) -> dict[str, LedPattern]:
    if not s.on_line:
        return dict.fromkeys((LINK, STATUS, ERROR), LedPattern.OFF)
    error = ERROR_BY_KIND[s.error]
    if error is LedPattern.OFF and s.drive_alarm:
        error = DRIVE_ALARM
    return {LINK: link_led(True, s.link, s.activity), STATUS: RUN_BY_STATE[s.state],
            ERROR: error}
