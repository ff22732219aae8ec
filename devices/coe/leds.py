"""The drive's EtherCAT LEDs (seed 004 ch. 5 "Connessioni e Leds Drive EtherCAT").

"L/A verde: Link Active rete ethernet" (one per RJ45, IN and OUT); "Status verde: segnalazione
dello stato ethercat. Se
sempre acceso ethercat è in operational mode ... ETG-1300"; "Error rosso: segnalazione
warning/allarmi in ethercat. La frequenza di lampeggio è funzione della tipologia di allarme
... ETG-1300". Status is the ETG.1300 RUN indicator and L/A its link/activity indicator (the
tables are the TRS-CAT's, which are ETG.1300's). Error is ETG.1300 ERR: the ESM's errors and
the drive alarms that are ETG.1300 causes; an alarm of the motor or the axis leaves it dark
(docs/ethercat-coe.md §LEDs). With c9 != 11 at power-up the ESC, powered with the drive, still
drives L/A (ETG.1300 puts them on the ESC); Status and Error, the EtherCAT application's, stay
dark (docs/ethercat-coe.md "LEDs of a drive with c9 != 11").
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.coe.esm import CONTROLLER_ALARMS, ErrorKind
from devices.ethercat import AlState
from devices.leds import RUN_BY_STATE, LedPattern, link_led
from devices.servo.leds import ERROR, LINK_IN, LINK_OUT, STATUS

__all__ = ["ERROR", "LINK_IN", "LINK_OUT", "STATUS", "LedInputs", "alarm_led",
           "wanted_patterns"]

# ETG.1300 ERR: blinking = invalid configuration, single flash = local error (the slave left
# its state on its own), double flash = process data watchdog timeout, flickering = booting
# error (INIT reached with the error indicator set: alarm 35, the EtherCAT EEPROM).
ERROR_BY_KIND: dict[ErrorKind, LedPattern] = {
    ErrorKind.NONE: LedPattern.OFF,
    ErrorKind.REFUSED: LedPattern.BLINKING,
    ErrorKind.LOCAL: LedPattern.SINGLE_FLASH,
    ErrorKind.WATCHDOG: LedPattern.DOUBLE_FLASH,
    ErrorKind.BOOTING: LedPattern.FLICKERING,
}
# The drive alarms (ch. 5 "Codici allarmi specifici") that are an ETG.1300 ERR cause by
# themselves: on = application controller failure (CONTROLLER_ALARMS: 7 "Processore DSP in
# fault", 30-32 the drive's internal communication; on in any ESM state, PREOP included).
# 33 / 34 / 35 come with their ESM error (refused SAFEOP, SM watchdog, INIT + EEPROM error:
# the flickering is the ESM's, so it cannot show next to a lit Status). Every other alarm
# leaves EtherCAT in working order: off.
ERROR_BY_ALARM: dict[int, LedPattern] = dict.fromkeys(sorted(CONTROLLER_ALARMS), LedPattern.ON)
# ETG.1300 ERR rows, most severe first (as the CPX-E-EC's Tab. 12, docs/cpx-e-ec.md choice 29)
_SEVERITY = (LedPattern.ON, LedPattern.FLICKERING, LedPattern.BLINKING,
             LedPattern.DOUBLE_FLASH, LedPattern.SINGLE_FLASH, LedPattern.OFF)
_RANK = {p: i for i, p in enumerate(_SEVERITY)}
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_OFF = LedPattern.OFF


def alarm_led(latched: list[int]) -> LedPattern:
    """The ERR pattern the latched drive alarms ask for by themselves (OFF for most)."""
    if not latched:
        return _OFF  # the usual case, checked every step
    found = [ERROR_BY_ALARM[c] for c in latched if c in ERROR_BY_ALARM]
    return min(found, key=_RANK.__getitem__, default=LedPattern.OFF)


@dataclass(frozen=True)
class LedInputs:
    esc: bool  # the drive powered: its ESC has its ports' links and passes frames, any c9
    on_line: bool  # powered, c9 = EtherCAT at power-up: the application drives Status, Error
    link: bool  # the IN port
    link_out: bool  # the OUT port: a next slave cabled and powered
    activity: bool
    state: AlState
    error: ErrorKind
    drive_alarm: LedPattern  # alarm_led() of the drive's latched alarms


def wanted_patterns(s: LedInputs) -> dict[str, LedPattern]:
    if not s.esc:
        return dict.fromkeys((LINK_IN, STATUS, LINK_OUT, ERROR), LedPattern.OFF)
    if s.on_line:
        status = RUN_BY_STATE[s.state]
        error = min(ERROR_BY_KIND[s.error], s.drive_alarm, key=_RANK.__getitem__)
    else:  # no EtherCAT application runs (c9 != 11): nothing drives RUN or ERR
        status = error = LedPattern.OFF
    # The frames that come in pass on through OUT while it has link (ETG.1300 L/A per port).
    return {LINK_IN: link_led(True, s.link, s.activity), STATUS: status,
            LINK_OUT: link_led(True, s.link_out, s.activity and s.link_out), ERROR: error}
