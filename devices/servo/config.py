"""How a rig sets up one servo drive: keypad defaults, mechanics and wiring."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from devices.names import did_you_mean
from devices.servo.errors import AccessError
from devices.servo.parameters import (
    C9_BY_FIELDBUS,
    FIELDBUS_BY_C9,
    PARAMETER_BY_NAME,
    check_node_number,
    node_range,
)
from devices.servo.plant import AxisGeometry
from devices.servo.registers import register_spec

BUS_NAMES = {"modbus": "Modbus", "canopen": "CANopen", "ethercat": "EtherCAT",
             "profinet": "PROFINET"}


@dataclass(frozen=True)
class DriveConfig:
    """One drive in a rig. Positions are user units at ``feed_constant`` units per motor turn."""

    #: c7 at first power-up: 1..90 on Modbus (seed 004 ch. 2), 1..99 otherwise (ch. 4)
    node_id: int = 1
    #: c9 at first power-up: "modbus" (3), "canopen" (5), "ethercat" (11), "profinet" (13)
    fieldbus: str = "modbus"
    #: R02 at first power-up, and the scale of the axis positions below
    feed_constant: int = 6000
    neg_limit: float = -60_000.0  # negative limit switch, active at and below
    pos_limit: float = 660_000.0  # positive limit switch, active at and above
    home_switch: float = -3_000.0  # home switch, active at and above
    marker_offset: float = 1_500.0  # one encoder marker per motor turn, the first one here
    start_position: float = 0.0  # where the carriage stands at power-on
    end_margin_turns: float = 1.0  # mechanical end stops beyond the limit switches
    max_speed_rpm: float = 3000.0  # the motor's rated speed (d3 = 100 % of it)
    position_lag_ms: float = 2.0  # position loop time constant at i1 = 50 %
    load_inertia: float = 1.0  # load / motor inertia (scales the current readings o1..o3)
    quick_stop_decel: float = 200.0  # emergency ramp at f3 = 50 %, rev/s^2
    ten_wired: bool = True  # TEN wired to 24 V (seed 004 ch. 2 example)
    ien_wired: bool = True  # IEN wired to 24 V
    parameters: Mapping[str, int] = field(default_factory=dict)  # keypad values at first power-up
    registers: Mapping[int, int] = field(default_factory=dict)  # register values likewise

    def __post_init__(self) -> None:
        if self.fieldbus not in C9_BY_FIELDBUS:
            raise ValueError(f"fieldbus {self.fieldbus!r} is not one of "
                             f"{', '.join(C9_BY_FIELDBUS)}"
                             f"{did_you_mean(str(self.fieldbus), C9_BY_FIELDBUS)}")
        # The range of the bus the drive powers up on (c9 in ``parameters`` overrides
        # fieldbus): "outside 1..99" for a Modbus node 500 sent the technician past the
        # reserved 91..255 (seed 004 ch. 2).
        given = {str(k).lower(): v for k, v in self.parameters.items()}
        c9 = given.get("c9", C9_BY_FIELDBUS[self.fieldbus])
        low, high = node_range(c9)
        if not low <= self.node_id <= high:
            bus = FIELDBUS_BY_C9.get(c9, "")
            raise ValueError(f"node_id {self.node_id} is outside {low}..{high} on "
                             f"{BUS_NAMES.get(bus, f'c9 = {c9}')} (parameter c7"
                             + ("; 91..255 are reserved, seed 004 ch. 2)"
                                if bus == "modbus" else ")"))
        if not 1 <= self.feed_constant <= 0x3FFFF:
            raise ValueError(f"feed_constant {self.feed_constant} is outside 1..0x3FFFF (R02)")
        if not self.neg_limit < self.pos_limit:
            raise ValueError("neg_limit must be below pos_limit")
        if not self.neg_limit < self.start_position < self.pos_limit:
            raise ValueError("start_position must lie between the limit switches")
        for name in ("max_speed_rpm", "position_lag_ms", "quick_stop_decel", "end_margin_turns"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be positive")
        if self.load_inertia < 0:
            raise ValueError("load_inertia must not be negative")
        for name, value in self.parameters.items():
            spec = PARAMETER_BY_NAME.get(str(name).lower())
            if spec is None:
                raise ValueError(f"parameters: there is no parameter {name!r}")
            try:
                spec.check(value)
            except AccessError as exc:
                raise ValueError(f"parameters: {exc}") from None
        # c7 / c9 in ``parameters`` override node_id / fieldbus at first power-up
        # (saving.py); a Modbus drive at 91..99 would sit on reserved addresses (ch. 2).
        try:
            check_node_number(given.get("c7", self.node_id),
                              given.get("c9", C9_BY_FIELDBUS[self.fieldbus]))
        except AccessError as exc:
            raise ValueError(f"node_id: {exc}") from None
        for number, value in self.registers.items():
            try:
                spec = register_spec(number)
                spec.check(value)
            except AccessError as exc:
                raise ValueError(f"registers: {exc}") from None
            if not spec.writable or number == 0:
                raise ValueError(f"registers: R{number:02d} {spec.name} cannot be preset")

    def geometry(self) -> AxisGeometry:
        """The axis in motor turns (the plant's unit)."""
        f = float(self.feed_constant)
        return AxisGeometry(self.neg_limit / f, self.pos_limit / f, self.home_switch / f,
                            self.marker_offset / f, self.end_margin_turns)
