"""The drive's 32-bit registers R00..R133 as data (seed 004 ch. 1 "Quick reference Registri").

Every register lives at Modbus address 0x8000 + n. Ranges are the quick reference's "contenuto"
column; ``0x80000000-0x7fffffff`` is S32 and ``0x8000-0x7fff`` is S16. The column printed "Si" /
"no" lost its header in the OCR; it matches, register for register, the list of objects that
chapter 4 says a flash save keeps (0x6060, 0x6092, 0x6065, ... 0x3701-0x3704) while measured
values and targets say "no", so it is read as "saved to flash" (docs/servo-drive.md §Registers).
Read-only flags are not printed in the quick reference: registers the drive computes (status,
measurements, alarm code, inputs) are read-only, as their CiA 402 twins in chapter 4 are.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass

from devices.servo.errors import AccessError

REGISTER_BASE = 0x8000
LAST_REGISTER = 133
S32 = (-0x8000_0000, 0x7FFF_FFFF)
S16 = (-0x8000, 0x7FFF)
U32 = (0, 0xFFFF_FFFF)
U31 = (0, 0x7FFF_FFFF)
DISABLED_32 = 0xFFFF_FFFF  # following_error_window: no following-error check (ch. 4, 0x6065)
DISABLED_16 = 0xFFFF  # velocity window / threshold: no check (ch. 4, 0x606D / 0x606F)


class R(enum.IntEnum):
    """Register numbers the model uses by name."""

    CONTROL_WORD = 0
    MODES_OF_OPERATION = 1
    FEED_CONSTANT = 2
    FOLLOWING_ERROR_WINDOW = 3
    FOLLOWING_ERROR_TIMEOUT = 4
    STATUS_WORD = 5
    POSITION_ACTUAL_VALUE = 6
    LATCHED_POSITION = 7
    VELOCITY_ACTUAL_VALUE = 8
    TARGET_POSITION = 9
    PROFILE_ACCELERATION = 10
    PROFILE_DECELERATION = 11
    PROFILE_VELOCITY = 12
    TARGET_VELOCITY = 13
    VELOCITY_WINDOW = 14
    VELOCITY_WINDOW_TIME = 15
    VELOCITY_THRESHOLD = 16
    VELOCITY_THRESHOLD_TIME = 17
    HOMING_METHOD = 18
    HOME_OFFSET = 19
    HOMING_FAST_SPEED = 20
    HOMING_SLOW_SPEED = 21
    HOMING_ACCELERATION = 22
    VELOCITY_MASTER_SENSOR = 23
    MASTER_ENCODER_INCREMENTS = 24
    GEAR_RATIO_NUMERATOR = 25
    GEAR_RATIO_DIVISOR = 26
    MOTION_PROFILE_TYPE = 27
    ACCELERATION_JERK = 28
    DECELERATION_JERK = 29
    AUX_IN_1 = 30
    ALARM_CODE = 46
    IP_TIME_UNITS = 47
    DIGITAL_INPUTS = 48
    DIGITAL_OUT_MASK = 49
    DIGITAL_OUTPUTS = 50
    TARGET_WINDOW = 61
    SPEED_RPM = 73


# Modes of operation (R01 / 0x6060, ch. 1 and ch. 4 "Oggetto 0x6060").
MODE_NAMES: dict[int, str] = {
    1: "positioner",
    3: "velocity",
    6: "homing",
    7: "interpolator",
    -1: "pulse positioner",
    -2: "electronic axis",
    -50: "save/load",
    -127: "analog reference",
}

# motion_profile_type (R27 / 0x6086, ch. 4): 0 trapezoidal, -1 S ramp, -2 sine ramp.
PROFILE_NAMES: dict[int, str] = {0: "trapezoidal", -1: "S (jerk)", -2: "sine"}


@dataclass(frozen=True)
class RegisterSpec:
    number: int
    name: str
    low: int
    high: int
    saveable: bool  # the quick reference's "Si" / "no" column
    writable: bool = True
    default: int = 0
    allowed: tuple[int, ...] | None = None  # a closed set of codes inside the range, in order

    @property
    def address(self) -> int:
        return REGISTER_BASE + self.number

    @property
    def signed(self) -> bool:
        return self.low < 0

    def normalize(self, value: int) -> int:
        """A 32-bit wire value as the register holds it (two's complement where signed)."""
        if isinstance(value, bool) or not isinstance(value, int):
            raise AccessError("value", f"R{self.number:02d} {self.name}: {value!r} is not an "
                                       "integer")
        if not -0x8000_0000 <= value <= 0xFFFF_FFFF:
            raise AccessError("value", f"R{self.number:02d} {self.name}: {value} does not fit "
                                       "32 bits")
        if self.signed and value > 0x7FFF_FFFF:
            value -= 1 << 32
        elif not self.signed and value < 0 and self.high > 0x7FFF_FFFF:
            value += 1 << 32
        return value

    def check(self, value: int) -> int:
        """The value to store, or AccessError ``value`` naming the allowed range."""
        value = self.normalize(value)
        if not self.low <= value <= self.high:
            raise AccessError("value", f"R{self.number:02d} {self.name} = {value} is outside "
                                       f"{_fmt_range(self)}")
        if self.allowed is not None and value not in self.allowed:
            codes = ", ".join(str(v) for v in sorted(self.allowed))
            raise AccessError("value", f"R{self.number:02d} {self.name} = {value} is not one of "
                                       f"{codes}")
        return value


def _fmt_range(spec: RegisterSpec) -> str:
    if spec.low < 0:
        return f"{spec.low}..{spec.high}"
    return f"0x{spec.low:X}..0x{spec.high:X}"


def _r(n: int, name: str, rng: tuple[int, int], saveable: bool, writable: bool = True,
       default: int = 0, allowed: Mapping[int, str] | None = None) -> RegisterSpec:
    return RegisterSpec(n, name, rng[0], rng[1], saveable, writable, default,
                        tuple(allowed) if allowed is not None else None)


# Defaults are not printed in the seed; each one is chosen in docs/servo-drive.md §Defaults.
_TABLE: tuple[RegisterSpec, ...] = (
    _r(0, "control_word", (0, 0xFFFF), True),
    _r(1, "modes_of_operation", (-0x7F, 0x7F), True, default=1, allowed=MODE_NAMES),
    _r(2, "feed_constant", (0, 0x3FFFF), True, default=6000),
    _r(3, "following_error_window", U32, True, default=1000),
    _r(4, "following_error_timeout", (0, 0x1FFF), True, default=100),
    _r(5, "status_word", (0, 0xFF), False, writable=False),
    _r(6, "position_actual_value", S32, False, writable=False),
    _r(7, "latched_position", S32, False),
    _r(8, "velocity_actual_value", S32, False, writable=False),
    _r(9, "target_position", S32, False),
    _r(10, "profile_acceleration", U31, True, default=100),
    _r(11, "profile_deceleration", U31, True, default=100),
    _r(12, "profile_velocity", U31, True, default=1000),
    _r(13, "target_velocity", S32, False),
    _r(14, "velocity_window", (0, 0xFFFF), True, default=100),
    _r(15, "velocity_window_time", (0, 0x7FFF), True, default=10),
    _r(16, "velocity_threshold", (0, 0xFFFF), True, default=100),
    _r(17, "velocity_threshold_time", (0, 0x7FFF), True, default=10),
    _r(18, "homing_method", (0, 0xFF), True, default=34),
    _r(19, "home_offset", S32, True),
    _r(20, "homing_fast_speed", S32, True, default=1000),
    _r(21, "homing_slow_speed", U31, True, default=100),
    _r(22, "homing_acceleration", U31, True, default=100),
    _r(23, "velocity_master_sensor", S16, False, writable=False),
    _r(24, "master_encoder_increments", (1, 0x7FFF), True, default=4096),
    _r(25, "gear_ratio_numerator", (1, 0x20), True, default=1),
    _r(26, "gear_ratio_divisor", (1, 0xFF), True, default=1),
    _r(27, "motion_profile_type", S16, True, allowed=PROFILE_NAMES),
    _r(28, "acceleration_jerk", (1, 0x63), True, default=50),
    _r(29, "deceleration_jerk", (1, 0x63), True, default=50),
    _r(30, "aux_in_1", S32, True),
    _r(31, "aux_in_2", S32, True),
    _r(32, "aux_out_1", S32, True, writable=False),  # 0x3301 ro (ch. 4)
    _r(33, "aux_out_2", S32, True, writable=False),  # 0x3302 ro
    _r(34, "aux_in_3", S32, True),
    _r(35, "torque_max", S16, True, default=100),  # CANopen 0x3402 as printed
    _r(36, "aux16_out_3", S16, True, writable=False),  # 0x3501 ro
    _r(37, "aux16_out_4", S16, True, writable=False),  # 0x3502 ro
    *(_r(n, f"aux_in_{n - 33}", S32, True) for n in range(38, 42)),
    _r(42, "aux16_in_9", S32, True),  # S32 as printed, unlike R43..R45
    *(_r(n, f"aux16_in_{n - 33}", S16, True) for n in range(43, 46)),
    _r(46, "alarm_code", (0, 0xFF), False, writable=False),
    _r(47, "ip_time_units", (0, 0xFF), True, default=1),
    _r(48, "digital_inputs", U32, False, writable=False),
    _r(49, "digital_out_mask", U32, True),
    _r(50, "digital_outputs", U32, True),
    *(_r(n, f"aux_in_{n - 38}", S32, True) for n in range(51, 61)),
    _r(61, "target_window", S32, True, default=100),
    _r(62, "abs_enc_control", S32, True),
    _r(63, "abs_enc_status", S32, True),
    _r(64, "num_ext_enc", S32, True, default=1),
    _r(65, "den_ext_enc", S32, True, default=1),
    *(_r(n, f"aux_mechatronic_{n}", S32, True) for n in range(66, 73)),
    _r(73, "speed_rpm", S32, True, writable=False),
    *(_r(n, f"aux_mechatronic_{n}", S32, True) for n in range(74, LAST_REGISTER + 1)),
)

REGISTERS: dict[int, RegisterSpec] = {spec.number: spec for spec in _TABLE}
REGISTER_BY_NAME: dict[str, RegisterSpec] = {spec.name: spec for spec in _TABLE}


def register_spec(n: int) -> RegisterSpec:
    spec = REGISTERS.get(n) if isinstance(n, int) and not isinstance(n, bool) else None
    if spec is None:
        last = REGISTER_BASE + LAST_REGISTER
        raise AccessError("address", f"there is no register R{n} (R00..R{LAST_REGISTER}, "
                                     f"0x{REGISTER_BASE:04X}..0x{last:04X})")
    return spec


def default_registers(overrides: Mapping[int, int] | None = None) -> dict[int, int]:
    """Power-on values of the stored registers (computed ones are not stored)."""
    values = {spec.number: spec.default for spec in _TABLE}
    for n, value in (overrides or {}).items():
        values[n] = REGISTERS[n].check(value)
    return values
