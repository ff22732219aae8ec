"""What every mode of operation is to the drive: the hooks it calls."""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive
    from devices.servo.modes import SpeedMonitor

Changes = list[tuple[str, bool, float]]


class Mode:
    number: ClassVar[int] = 0
    #: the velocity modes' speed monitor: the drive feeds it the speed every tick (zero speed)
    monitor: SpeedMonitor | None = None

    @property
    def busy(self) -> bool:
        """A procedure that owns the limit switches is running (homing)."""
        return False

    def enter(self, d: ServoDrive) -> None:
        d.trajectory.stop(d.limits())

    def torque_on(self, d: ServoDrive) -> None:
        """The axis just went into torque, standing where it is."""

    def on_controlword(self, d: ServoDrive, rising: int, falling: int) -> None:
        """Edges of the controlword (0x6040 view) while this mode is active."""

    def on_start_input(self, d: ServoDrive) -> None:
        """Rising edge of the Start input (CN2 pin 1)."""

    def step(self, d: ServoDrive, dt: float) -> None:
        """Motion is allowed: plan the trajectory for this tick."""

    def halted(self, d: ServoDrive) -> None:
        """Motion stopped being allowed (halt, quick stop, IEN, torque off, alarm)."""

    def observe(self, d: ServoDrive, changes: Changes) -> None:
        """Signal changes after the motor moved this tick."""

    def flags(self, d: ServoDrive) -> dict[str, bool]:
        return {}

    def end_of_job(self, d: ServoDrive) -> bool:
        return False

    def near_target(self, d: ServoDrive) -> bool:
        return False

    def target_reached(self, d: ServoDrive) -> bool:
        return d.trajectory.idle and d.trajectory.velocity == 0.0
