"""Which LED pattern the FastCAT coupler and its modules show, from the coupler's state.

Coupler LEDs follow ETG.1300 (patterns and timings in devices/leds.py): RUN by ESM state, ERR
by error kind, LINK by cable and traffic. Module LEDs follow seed 000 §2: red steady when the
module is recognised during a scan and while the configuration differs from the stored one,
yellow blinking while the internal bus is active. Table in docs/fastcat-coupler.md.
"""

from __future__ import annotations

import enum

from devices.ethercat import AlState
from devices.fastcat.alarms import COUPLER, Alarm
from devices.fastcat.cnf import BusScan, ScanPhase
from devices.fastcat.esm import ErrorKind
from devices.leds import RUN_BY_STATE, LedPattern

# ETG.1300 ERR indicator: "blinking = invalid configuration", "flickering = booting error",
# "single flash = local error". Latched alarms that say the hardware configuration is wrong
# (§2 mismatch, §7.5 0x14, 0x15) blink; finding no module at all is a booting error.
ERR_BY_ALARM: dict[tuple[str, int], LedPattern] = {
    (COUPLER, 0x01): LedPattern.BLINKING,
    (COUPLER, 0x02): LedPattern.BLINKING,
    (COUPLER, 0x14): LedPattern.BLINKING,
    (COUPLER, 0x15): LedPattern.BLINKING,
    (COUPLER, 0x10): LedPattern.FLICKERING,
}
ERR_BY_ESM_ERROR: dict[ErrorKind, LedPattern] = {
    ErrorKind.NONE: LedPattern.OFF,
    ErrorKind.REFUSED: LedPattern.BLINKING,
    ErrorKind.AUTONOMOUS: LedPattern.SINGLE_FLASH,
    # ETG.1300 "double flash: an application watchdog timeout has occurred"; the SSC shows it
    # for AL status code 0x001B with the error flag, whether the slave fell or refused OP
    ErrorKind.WATCHDOG: LedPattern.DOUBLE_FLASH,
}


def run_led(powered: bool, state: AlState) -> LedPattern:
    return RUN_BY_STATE[state] if powered else LedPattern.OFF


def err_led(powered: bool, alarm: Alarm | None, esm_error: ErrorKind) -> LedPattern:
    if not powered:
        return LedPattern.OFF
    if alarm is not None and (alarm.table, alarm.code) in ERR_BY_ALARM:
        return ERR_BY_ALARM[(alarm.table, alarm.code)]
    pattern = ERR_BY_ESM_ERROR[esm_error]
    if pattern is LedPattern.OFF and alarm is not None and alarm.holds_esm:
        # A coupler alarm is a local error even before a refusal. A module alarm sets no error
        # flag and keeps the ESM: ERR follows the flag (ETG.1300), the module reds show it.
        return LedPattern.SINGLE_FLASH
    return pattern


class ModuleLight(enum.Enum):
    """What a module's pair of LEDs says (seed 000 §2, §7)."""

    DARK = "dark"  # no power, not on the bus, or not yet recognised
    RECOGNISED = "recognised"  # found by the running scan
    ACTIVE = "active"  # internal bus active
    ALARM = "alarm"  # coupler in alarm (a mismatch included): every module in alarm


MODULE_LEDS: dict[ModuleLight, tuple[LedPattern, LedPattern]] = {  # (red, yellow)
    ModuleLight.DARK: (LedPattern.OFF, LedPattern.OFF),
    ModuleLight.RECOGNISED: (LedPattern.ON, LedPattern.OFF),
    ModuleLight.ACTIVE: (LedPattern.OFF, LedPattern.BLINKING),
    ModuleLight.ALARM: (LedPattern.ON, LedPattern.OFF),
}


def module_light(alive: bool, slot: int, scan: BusScan | None, now_us: int, addressed: bool,
                 in_alarm: bool) -> ModuleLight:
    """``alive``: coupler and module powered, module on the rail and working;
    ``addressed``: the last scan numbered it."""
    if not alive:
        return ModuleLight.DARK
    if scan is not None:
        phase = scan.phase(now_us)
        if phase is ScanPhase.RESETTING:
            return ModuleLight.DARK
        if phase is ScanPhase.SCANNING:  # §2: red steady as each module is recognised
            seen = scan.slots[:scan.recognised(now_us)]
            return ModuleLight.RECOGNISED if slot in seen else ModuleLight.DARK
        if phase is ScanPhase.STORING:  # §2: the yellow LEDs blink when the scan is over
            return ModuleLight.ACTIVE if slot in scan.slots else ModuleLight.DARK
    if not addressed:
        return ModuleLight.DARK
    return ModuleLight.ALARM if in_alarm else ModuleLight.ACTIVE


def module_led_patterns(slot: int, light: ModuleLight) -> dict[str, LedPattern]:
    red, yellow = MODULE_LEDS[light]
    return {f"{slot}.red": red, f"{slot}.yellow": yellow}
