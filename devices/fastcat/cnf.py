"""The CNF push-button and the internal-bus scan timeline (seed 000 §2, §3).

§2: CNF held for at least three seconds, then released: the coupler resets every module on the
internal bus, scans it (each module's red LED turns steady as it is recognised, one after the
other), then the yellow LEDs of all detected modules blink and the configuration is stored.
§3: a scan also runs on every return to INIT and takes "some seconds" that depend on the
number of modules. The durations below are FieldRig's choice (docs/fastcat-coupler.md).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

CNF_MIN_HOLD_US = 3_000_000  # §2 "almeno tre secondi"
CNF_RESET_US = 500_000  # modules held in reset before the CNF scan
SCAN_SETUP_US = 1_000_000  # bus reset and start of address assignment
SCAN_PER_MODULE_US = 250_000  # one bus position probed; one more to find the end of the bus
FLASH_WRITE_US = 100_000  # writing the detected configuration to flash


class ScanPhase(enum.Enum):
    IDLE = "idle"
    RESETTING = "resetting"  # CNF only: all modules reset, LEDs off
    SCANNING = "scanning"  # red LEDs turn steady one by one
    STORING = "storing"  # CNF only: yellow LEDs blink, the configuration goes to flash


@dataclass
class CnfButton:
    """The physical button: when it went down and, for a timed hold, when it comes up."""

    pressed: bool = False
    pressed_at_us: int = 0
    release_at_us: int | None = None

    def press(self, now_us: int, hold_us: int | None = None) -> None:
        """Push (``hold_us`` None: until :meth:`release`) or push for ``hold_us`` from now.

        On a button already down the hold still counts from when it went down. A timed press
        gives an open-ended hold its end; over a timed press it can only keep the button down
        longer (it is still held until the first one's end). An open-ended press keeps it down
        until released (docs/fastcat-coupler.md, "CNF button").
        """
        if not self.pressed:
            self.pressed = True
            self.pressed_at_us = now_us
            self.release_at_us = None
        if hold_us is None:
            self.release_at_us = None
            return
        end, was = now_us + hold_us, self.release_at_us
        self.release_at_us = end if was is None else max(was, end)

    def release(self, now_us: int) -> int | None:
        """Let go; returns how long it was held, or None if it was not pressed.

        A timed hold counts to its scheduled instant, not to the step that noticed it, so a
        3.0 s hold is 3.0 s whatever the clock step.
        """
        if not self.pressed:
            return None
        end = self.release_at_us
        if end is None or end > now_us:
            end = now_us
        self.pressed = False
        self.release_at_us = None
        return end - self.pressed_at_us

    def held_us(self, now_us: int) -> int:
        return now_us - self.pressed_at_us if self.pressed else 0

    def release_due(self, now_us: int) -> bool:
        return self.pressed and self.release_at_us is not None and now_us >= self.release_at_us

    @staticmethod
    def long_enough(held_us: int) -> bool:
        return held_us >= CNF_MIN_HOLD_US


@dataclass
class BusScan:
    """One scan in progress. ``slots``: the rail slots that answered, in bus order."""

    start_us: int
    slots: tuple[int, ...]
    cnf: bool = False
    detected_applied: bool = False  # the coupler has taken the result (OD built, LEDs on)

    @property
    def scanning_from_us(self) -> int:
        return self.start_us + (CNF_RESET_US if self.cnf else 0)

    @property
    def scan_end_us(self) -> int:
        return (self.scanning_from_us + SCAN_SETUP_US
                + (len(self.slots) + 1) * SCAN_PER_MODULE_US)

    @property
    def end_us(self) -> int:
        return self.scan_end_us + (FLASH_WRITE_US if self.cnf else 0)

    def phase(self, now_us: int) -> ScanPhase:
        if now_us < self.scanning_from_us:
            return ScanPhase.RESETTING
        if now_us < self.scan_end_us:
            return ScanPhase.SCANNING
        if now_us < self.end_us:
            return ScanPhase.STORING
        return ScanPhase.IDLE

    def recognised(self, now_us: int) -> int:
        """How many modules have been recognised (their red LED is on) at ``now_us``."""
        elapsed = now_us - self.scanning_from_us - SCAN_SETUP_US
        if elapsed < SCAN_PER_MODULE_US:
            return 0
        return min(len(self.slots), elapsed // SCAN_PER_MODULE_US)

    def scanned(self, now_us: int) -> bool:
        return now_us >= self.scan_end_us

    def finished(self, now_us: int) -> bool:
        return now_us >= self.end_us
