"""The one simulation clock of a rig: integer microseconds, a fixed step."""

from __future__ import annotations

from dataclasses import dataclass

DEFAULT_STEP_US = 1_000  # one EtherCAT cycle of the built-in master


@dataclass
class SimClock:
    step_us: int = DEFAULT_STEP_US
    now_us: int = 0

    def __post_init__(self) -> None:
        if self.step_us <= 0:
            raise ValueError(f"clock step must be positive, got {self.step_us} us")

    def tick(self) -> int:
        self.now_us += self.step_us
        return self.now_us

    @property
    def now_s(self) -> float:
        return self.now_us / 1_000_000
