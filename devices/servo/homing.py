"""Homing methods (R18 / 0x6098) as data, the sequence that runs one, and mode 6 itself.

Seed 004 ch. 4 "Modo Homing": method 34 searches the marker in the positive direction at the
slow speed (0x6099:2) with the homing acceleration (0x609A); the fast speed is not used; after
homing with home offset -1000 the actual position reads 1000, i.e. the home point takes the
position -home_offset. The Modbus example (ch. 2) uses method 33 (0x21), the marker in the
negative direction. The switch methods follow DSP 402 ch. 13 for the hardware of
:mod:`devices.servo.plant` (limit switches, a positive home switch); docs/servo-drive.md
§Homing lists them. Searches for a switch run at the fast speed, searches for the marker or a
switch edge at the slow one.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TYPE_CHECKING

from devices.servo import ds402
from devices.servo.mode_base import Changes, Mode
from devices.servo.motion import Limits
from devices.servo.registers import R

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive


class Until(enum.Enum):
    """The signal change that ends a search phase."""

    NEG_LIMIT_ON = ("neg_limit", True)
    NEG_LIMIT_OFF = ("neg_limit", False)
    POS_LIMIT_ON = ("pos_limit", True)
    POS_LIMIT_OFF = ("pos_limit", False)
    HOME_ON = ("home", True)
    HOME_OFF = ("home", False)
    MARKER = ("marker", True)

    @property
    def signal(self) -> str:
        return self.value[0]

    @property
    def level(self) -> bool:
        return self.value[1]


@dataclass(frozen=True)
class Phase:
    direction: int  # +1 positive, -1 negative
    fast: bool  # fast (switch search) or slow (marker / edge search) speed
    until: Until


@dataclass(frozen=True)
class HomingMethod:
    number: int
    description: str
    phases: tuple[Phase, ...]  # when the home switch is off at the start
    phases_on_home: tuple[Phase, ...] | None = None  # when it is on (methods 3, 4, 19, 20)
    limits: frozenset[str] = frozenset()  # limit switches it searches: the only ones it uses

    def plan(self, home_switch_on: bool) -> tuple[Phase, ...]:
        if home_switch_on and self.phases_on_home is not None:
            return self.phases_on_home
        return self.phases


P, U = Phase, Until
NEG, POS = frozenset({"neg_limit"}), frozenset({"pos_limit"})
METHODS: dict[int, HomingMethod] = {m.number: m for m in (
    HomingMethod(1, "negative limit switch, then the marker",
                 (P(-1, True, U.NEG_LIMIT_ON), P(+1, False, U.NEG_LIMIT_OFF),
                  P(+1, False, U.MARKER)), limits=NEG),
    HomingMethod(2, "positive limit switch, then the marker",
                 (P(+1, True, U.POS_LIMIT_ON), P(-1, False, U.POS_LIMIT_OFF),
                  P(-1, False, U.MARKER)), limits=POS),
    HomingMethod(3, "home switch, the marker below its edge",
                 (P(+1, True, U.HOME_ON), P(-1, False, U.HOME_OFF), P(-1, False, U.MARKER)),
                 (P(-1, False, U.HOME_OFF), P(-1, False, U.MARKER))),
    HomingMethod(4, "home switch, the marker above its edge",
                 (P(+1, True, U.HOME_ON), P(+1, False, U.MARKER)),
                 (P(-1, True, U.HOME_OFF), P(+1, False, U.HOME_ON), P(+1, False, U.MARKER))),
    HomingMethod(17, "negative limit switch edge",
                 (P(-1, True, U.NEG_LIMIT_ON), P(+1, False, U.NEG_LIMIT_OFF)), limits=NEG),
    HomingMethod(18, "positive limit switch edge",
                 (P(+1, True, U.POS_LIMIT_ON), P(-1, False, U.POS_LIMIT_OFF)), limits=POS),
    HomingMethod(19, "home switch edge, approached from above",
                 (P(+1, True, U.HOME_ON), P(-1, False, U.HOME_OFF)),
                 (P(-1, False, U.HOME_OFF),)),
    HomingMethod(20, "home switch edge, approached from below",
                 (P(+1, True, U.HOME_ON), P(-1, False, U.HOME_OFF), P(+1, False, U.HOME_ON)),
                 (P(-1, True, U.HOME_OFF), P(+1, False, U.HOME_ON))),
    HomingMethod(33, "marker in the negative direction", (P(-1, False, U.MARKER),)),
    HomingMethod(34, "marker in the positive direction", (P(+1, False, U.MARKER),)),
    HomingMethod(35, "the current position", ()),
)}
del P, U
HOMING_ALARM = 14  # HOMING, "homing error" (ch. 3): what a failed or unsupported run raises
NO_LIMITS: frozenset[str] = frozenset()


def limits_used(method: int) -> frozenset[str]:
    """The limit switch inputs homing method ``method`` (R18 / 0x6098) uses. Only those act as
    limit switches; the others are generic digital inputs (seed 004 ch. 2 l. 1488-1494, ch. 4
    l. 3910-3917: homing on the home switch alone frees pins 8 and 9). An unsupported method
    uses none."""
    found = METHODS.get(method)
    return found.limits if found is not None else NO_LIMITS


class HomingStatus(enum.Enum):
    IDLE = "idle"
    SEARCHING = "searching"
    RETURNING = "returning to the home point"
    ATTAINED = "attained"
    INTERRUPTED = "interrupted"
    ERROR = "error"


@dataclass
class HomingRun:
    """One homing, phase by phase. The drive feeds it the signal changes it sees."""

    method: HomingMethod
    phases: tuple[Phase, ...]
    index: int = 0
    home: float | None = None  # motor position of the home point once found

    @classmethod
    def start(cls, method: HomingMethod, home_switch_on: bool) -> HomingRun:
        return cls(method, method.plan(home_switch_on))

    @property
    def phase(self) -> Phase | None:
        return self.phases[self.index] if self.index < len(self.phases) else None

    def skip_satisfied(self, levels: dict[str, bool], position: float) -> None:
        """Phases whose switch condition already holds end at once (e.g. already on NL)."""
        while (phase := self.phase) is not None and phase.until is not Until.MARKER \
                and levels[phase.until.signal] == phase.until.level:
            self.index += 1
        if self.phase is None and self.home is None:
            self.home = position

    def observe(self, changes: list[tuple[str, bool, float]]) -> bool:
        """Signal changes of one step (signal, new level, position); True when a phase ended."""
        ended = False
        for signal, level, position in changes:
            phase = self.phase
            if phase is None:
                break
            if phase.until.signal == signal and phase.until.level == level:
                self.index += 1
                ended = True
                if self.phase is None:
                    self.home = position
        return ended


class Homing(Mode):
    """Mode 6: controlword bit 4 (R00 bit 6) 0 -> 1 starts, 1 -> 0 interrupts."""

    number = 6

    def __init__(self) -> None:
        self.status = HomingStatus.IDLE
        self.run: HomingRun | None = None

    def on_controlword(self, d: ServoDrive, rising: int, falling: int) -> None:
        if rising & ds402.CW_NEW_SET_POINT:
            self.begin(d)
        elif falling & ds402.CW_NEW_SET_POINT and self.busy:
            self.interrupt(d, "start bit cleared")

    @property
    def busy(self) -> bool:
        return self.status in (HomingStatus.SEARCHING, HomingStatus.RETURNING)

    def begin(self, d: ServoDrive) -> None:
        if not d.motion_allowed:
            return
        d.homed = False
        method = METHODS.get(d.reg(R.HOMING_METHOD))
        if method is None:
            self.fail(d, f"homing method {d.reg(R.HOMING_METHOD)} is not supported")
            return
        levels = d.input_levels()
        self.status = HomingStatus.SEARCHING
        self.run = HomingRun.start(method, levels["home"])
        self.run.skip_satisfied(levels, d.plant.theta)
        d.log(f"homing method {method.number} ({method.description}) started")
        self.next_phase(d)

    def limits(self, d: ServoDrive, speed_user: float) -> Limits:
        """R20 / R21 with R22, clamped to Vmax: d3 "Velocità massima del motore" (ch. 1)
        limits every speed, as in the other modes."""
        acc = d.accel_to_rev(d.reg(R.HOMING_ACCELERATION))
        return Limits(min(abs(d.speed_to_rev(speed_user)), d.motor_vmax_rev), acc, acc)

    def next_phase(self, d: ServoDrive) -> None:
        assert self.run is not None
        phase = self.run.phase
        slow = d.reg(R.HOMING_SLOW_SPEED)
        if phase is None:
            assert self.run.home is not None
            d.set_home(self.run.home)
            self.status = HomingStatus.RETURNING
            d.trajectory.move_to(self.run.home, self.limits(d, slow))
            return
        speed = abs(d.reg(R.HOMING_FAST_SPEED)) if phase.fast else slow
        lim = self.limits(d, speed)
        d.trajectory.run_at(phase.direction * lim.vmax, lim)

    def observe(self, d: ServoDrive, changes: Changes) -> None:
        if self.status is not HomingStatus.SEARCHING or self.run is None:
            return
        # a limit input the method does not search is a digital input for it (limits_used):
        # the search runs on, to the end stop and alarm 16 if nothing ends it before
        if self.run.observe(changes):
            self.next_phase(d)

    def step(self, d: ServoDrive, dt: float) -> None:
        if self.status is HomingStatus.RETURNING and d.trajectory.at_target \
                and abs(d.following_error_user) < 0.5:  # the home point reads exactly
            self.status = HomingStatus.ATTAINED
            d.homed = True
            d.log(f"homing attained, position {d.position_user}")

    def halted(self, d: ServoDrive) -> None:
        if self.busy:
            self.interrupt(d, "motion stopped")

    def interrupt(self, d: ServoDrive, why: str) -> None:
        self.status = HomingStatus.INTERRUPTED
        d.trajectory.stop(d.limits())
        d.log(f"homing interrupted: {why}")

    def fail(self, d: ServoDrive, why: str) -> None:
        self.status = HomingStatus.ERROR
        d.log(f"homing error: {why}")
        d.raise_alarm(HOMING_ALARM)

    def flags(self, d: ServoDrive) -> dict[str, bool]:
        return {"homing_attained": self.status is HomingStatus.ATTAINED,
                "homing_error": self.status in (HomingStatus.ERROR, HomingStatus.INTERRUPTED)}

    def end_of_job(self, d: ServoDrive) -> bool:
        return self.status is HomingStatus.ATTAINED

    def target_reached(self, d: ServoDrive) -> bool:
        return not self.busy and super().target_reached(d)
