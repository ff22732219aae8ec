"""LED indicator patterns and their timings (ETG.1300 "Indicator and labeling").

The phase of every pattern is taken from the simulated clock, not from when the pattern
started, so that all LEDs of a rig blink in step (as ETG.1300 asks of RUN and ERR) and a
screenshot at a given simulated time is always the same picture. See docs/leds.md.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from devices.ethercat import AlState
from devices.events import Event, LedChanged


class LedPattern(enum.Enum):
    OFF = "off"
    ON = "on"
    FLICKERING = "flickering"
    BLINKING = "blinking"
    SINGLE_FLASH = "single_flash"
    DOUBLE_FLASH = "double_flash"
    TRIPLE_FLASH = "triple_flash"


# (on_ms, off_ms, on_ms, off_ms, ...) for one period, starting lit. ETG.1300 §5:
# flickering 50/50 ms (10 Hz), blinking 200/200 ms (2.5 Hz), single flash 200 on 1000 off,
# double flash 200 on 200 off 200 on 1000 off, triple flash likewise with three flashes.
PATTERN_TIMING_MS: dict[LedPattern, tuple[int, ...]] = {
    LedPattern.FLICKERING: (50, 50),
    LedPattern.BLINKING: (200, 200),
    LedPattern.SINGLE_FLASH: (200, 1000),
    LedPattern.DOUBLE_FLASH: (200, 200, 200, 1000),
    LedPattern.TRIPLE_FLASH: (200, 200, 200, 200, 200, 1000),
}


def is_lit(pattern: LedPattern, t_us: int) -> bool:
    """Whether an LED showing ``pattern`` is lit at simulated time ``t_us``."""
    if pattern is LedPattern.OFF:
        return False
    if pattern is LedPattern.ON:
        return True
    timing = PATTERN_TIMING_MS[pattern]
    phase_ms = (t_us // 1000) % sum(timing)
    lit = True
    for span in timing:
        if phase_ms < span:
            return lit
        phase_ms -= span
        lit = not lit
    return False  # unreachable: the spans sum to the period


# ETG.1300 RUN indicator, the same on every slave that follows it (the FastCAT, the TRS-CAT, the
# drive's CoE Status LED); the CPX-E-EC's two-colour Run has its own table (seed 002 Tab. 11).
RUN_BY_STATE: dict[AlState, LedPattern] = {
    AlState.INIT: LedPattern.OFF,
    AlState.PREOP: LedPattern.BLINKING,
    AlState.SAFEOP: LedPattern.SINGLE_FLASH,
    AlState.OP: LedPattern.ON,
    AlState.BOOT: LedPattern.FLICKERING,
}


def link_led(powered: bool, link: bool, activity: bool) -> LedPattern:
    """ETG.1300 L/A: off = no link, flickering = link and traffic, on = link, no traffic."""
    if not powered or not link:
        return LedPattern.OFF
    return LedPattern.FLICKERING if activity else LedPattern.ON


@dataclass
class LedBank:
    """The last pattern of every single-colour LED of a device; emits LedChanged only when a
    pattern changes, and an LED no longer wanted goes dark (a module unplugged)."""

    device: str
    patterns: dict[str, LedPattern] = field(default_factory=dict)

    def update(self, t_us: int, wanted: Mapping[str, LedPattern],
               emit: Callable[[Event], None]) -> None:
        patterns = self.patterns
        for name, pattern in wanted.items():
            if patterns.get(name, LedPattern.OFF) is not pattern:
                emit(LedChanged(t_us, self.device, led=name, pattern=pattern.value))
            patterns[name] = pattern
        # Every wanted name is in ``patterns`` now: more names means some are no longer wanted.
        if len(patterns) > len(wanted):
            for name in [n for n in patterns if n not in wanted]:
                if patterns.pop(name) is not LedPattern.OFF:
                    emit(LedChanged(t_us, self.device, led=name,
                                    pattern=LedPattern.OFF.value))

    def snapshot(self) -> dict[str, str]:
        return {name: pattern.value for name, pattern in self.patterns.items()}
