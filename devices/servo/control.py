"""The register-mode control word R00 and status word R05, and how they map onto CiA 402.

Seed 004 ch. 1 (quick reference, R00 / R05 bit tables): bits 0-4 are the same in every mode,
bits 5-7 are "specifico del modo selezionato". Both status words are built from one
:class:`StatusFlags`, so R05 and 0x6041 can never disagree; a write of either control word is
translated into the other (docs/servo-drive.md §Two views) so that both always describe the
same command.
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.servo import ds402
from devices.servo.ds402 import State

TEN_CMD = 0x01
IEN_CMD = 0x02
STP_CMD = 0x04
ALM_RST = 0x08
LTC_RST = 0x10
BIT5 = 0x20
BIT6 = 0x40
BIT7 = 0x80

# The stop / halt bit as a master of each fieldbus sees it (the panel's notice), beside
# alarms.RESET_HINT: Modbus Stp_cmd, R00 bit 2 (ch. 1); CANopen and CoE 0x6040 bit 8 halt
# (ch. 4, DSP 402); Profinet's Control Word is R00 (ch. 6 example), so Stp_cmd, bit 2.
HALT_HINT: dict[str, str] = {
    "modbus": "stopped (Stp_cmd, R00 bit 2)",
    "canopen": "halted (0x6040 bit 8)",
    "ethercat": "halted (0x6040 bit 8)",
    "profinet": "stopped (Stp_cmd, Control Word bit 2)",
}
HALT_HINT_ANY = "halted (R00 bit 2 or 0x6040 bit 8)"  # c9 names no fieldbus: both views

POSITIONER = frozenset({1, -1})
VELOCITY = frozenset({3, -127})
SPEED_SET_POINT = frozenset({3})  # R13 target_velocity; -127 follows the analog input
HOMING = frozenset({6})
INTERPOLATOR = frozenset({7})
ELECTRONIC_AXIS = frozenset({-2})
SAVE_LOAD = frozenset({-50})

_COMMON_CW = {0: "Ten_cmd", 1: "Ien_cmd", 2: "Stp_cmd", 3: "Alm_rst", 4: "Ltc_rst"}
_COMMON_SW = {0: "Ten_st", 1: "Ien_st", 2: "Stp_st", 3: "Alm_st", 4: "Ltc_st"}

# Mode-specific bit names, as the quick reference prints them.
_MODE_CW: tuple[tuple[frozenset[int], dict[int, str]], ...] = (
    (POSITIONER, {5: "Pos_str", 6: "Upd_mod", 7: "Inc_mod"}),
    (INTERPOLATOR, {5: "Ip_str"}),
    (SAVE_LOAD, {5: "Save", 6: "Load"}),
    (HOMING, {6: "Homing_start"}),
    # Start/stop: bit 6 in the quick reference, bit 5 in ch. 2 "I/O digitali"; either engages
    (ELECTRONIC_AXIS, {5: "Axis_start", 6: "Axis_start"}),
)
_MODE_SW: tuple[tuple[frozenset[int], dict[int, str]], ...] = (
    (POSITIONER, {5: "sp_rdy", 6: "EOJ", 7: "Following_error"}),
    (VELOCITY, {7: "Zero_velocity"}),  # -127: speed control too (docs/servo-drive.md)
    (HOMING, {6: "Homing_ok", 7: "Homing_error"}),
    (INTERPOLATOR, {5: "Ip_st"}),
    (ELECTRONIC_AXIS, {6: "Axis_started"}),
    (SAVE_LOAD, {5: "Save_done", 6: "Load_done"}),
)
# What "1" means for each R05 bit, in English from the quick reference's column ("1: asse in
# coppia", "1: rampa di stop in corso", ...): the Drive tab's tooltips.
STATUS_BIT_MEANING: dict[str, str] = {
    "Ten_st": "in torque", "Ien_st": "motion enabled", "Stp_st": "stop ramp running",
    "Alm_st": "in alarm", "Ltc_st": "position latched", "sp_rdy": "ready for a set-point",
    "EOJ": "End of Job", "Following_error": "following error", "Zero_velocity": "zero speed",
    "Homing_ok": "homing OK", "Homing_error": "homing error", "Ip_st": "interpolator active",
    "Axis_started": "electronic axis started", "Save_done": "save done",
    "Load_done": "load done",
}
STATUS_ERROR_NAMES = frozenset({"Alm_st", "Following_error", "Homing_error"})
# 0x6041 bits 12 / 13 in words, per mode family, as cia402_status sets them: DSP 402 for pp,
# pv and ip, ch. 4 for homing ("bit 12 ... completata con successo", "bit 13 ... homing
# interrotto"); -127 and -2 are manufacturer modes that report zero speed and axis started
# there as R05 does (docs/servo-drive.md "Status words").
_MODE_SW_6041: tuple[tuple[frozenset[int], dict[int, str]], ...] = (
    (POSITIONER, {12: "set-point acknowledge", 13: "following error"}),
    (VELOCITY, {12: "speed = 0"}),
    (HOMING, {12: "homing attained", 13: "homing error"}),
    (INTERPOLATOR, {12: "ip mode active"}),
    (ELECTRONIC_AXIS, {12: "axis started"}),
)
_MODE_SW_6041_ERRORS = frozenset({13})  # following error (pp), homing error (hm)


def _names(common: dict[int, str], table: tuple[tuple[frozenset[int], dict[int, str]], ...],
           mode: int) -> dict[int, str]:
    out = dict(common)
    for modes, names in table:
        if mode in modes:
            out.update(names)
    return out


def control_bit_names(mode: int) -> dict[int, str]:
    return _names(_COMMON_CW, _MODE_CW, mode)


def status_bit_names(mode: int) -> dict[int, str]:
    return _names(_COMMON_SW, _MODE_SW, mode)


def statusword_mode_names(mode: int) -> dict[int, str]:
    """0x6041 bits 12 / 13 in words for ``mode`` (none in save / load)."""
    return _names({}, _MODE_SW_6041, mode)


def statusword_error_bits(mode: int) -> frozenset[int]:
    """The 0x6041 bits that report trouble in ``mode``: fault, warning, internal limit,
    and bit 13 where the mode gives it a meaning (following error, homing error)."""
    return ds402.STATUSWORD_ERROR_BITS | (_MODE_SW_6041_ERRORS
                                          & set(statusword_mode_names(mode)))


def controlword_from_register(r00: int, mode: int) -> int:
    """The 0x6040 value that commands what R00 commands (Ien_cmd has no 0x6040 bit)."""
    cw = 0
    if r00 & TEN_CMD:
        cw |= ds402.CW_SWITCH_ON | ds402.CW_ENABLE_VOLTAGE | ds402.CW_QUICK_STOP \
            | ds402.CW_ENABLE_OPERATION
    if r00 & STP_CMD:
        cw |= ds402.CW_HALT
    if r00 & ALM_RST:
        cw |= ds402.CW_FAULT_RESET
    if r00 & LTC_RST:
        cw |= ds402.CW_LATCH_RESET
    if mode in POSITIONER:
        cw |= _bit(r00 & BIT5, ds402.CW_NEW_SET_POINT) | _bit(r00 & BIT6,
                                                              ds402.CW_CHANGE_IMMEDIATELY)
        cw |= _bit(r00 & BIT7, ds402.CW_RELATIVE)
    elif mode in INTERPOLATOR:
        cw |= _bit(r00 & BIT5, ds402.CW_NEW_SET_POINT)
    elif mode in HOMING:
        cw |= _bit(r00 & BIT6, ds402.CW_NEW_SET_POINT)
    elif mode in ELECTRONIC_AXIS:
        # Quick reference: bit 6; the I/O chapter says bit 5 (as printed): either starts.
        cw |= _bit(r00 & (BIT5 | BIT6), ds402.CW_AXIS_START)
    return cw


def register_from_controlword(cw: int, mode: int, ien_cmd: bool) -> int:
    """The R00 value that commands what a 0x6040 value commands."""
    r00 = 0
    if cw & 0x000F == 0x000F:
        r00 |= TEN_CMD | (IEN_CMD if ien_cmd else 0)
    r00 |= _bit(cw & ds402.CW_HALT, STP_CMD) | _bit(cw & ds402.CW_FAULT_RESET, ALM_RST)
    r00 |= _bit(cw & ds402.CW_LATCH_RESET, LTC_RST)
    if mode in POSITIONER:
        r00 |= _bit(cw & ds402.CW_NEW_SET_POINT, BIT5)
        r00 |= _bit(cw & ds402.CW_CHANGE_IMMEDIATELY, BIT6) | _bit(cw & ds402.CW_RELATIVE, BIT7)
    elif mode in INTERPOLATOR:
        r00 |= _bit(cw & ds402.CW_NEW_SET_POINT, BIT5)
    elif mode in HOMING:
        r00 |= _bit(cw & ds402.CW_NEW_SET_POINT, BIT6)
    elif mode in ELECTRONIC_AXIS:
        r00 |= _bit(cw & ds402.CW_AXIS_START, BIT6)
    return r00


def _bit(condition: int | bool, bit: int) -> int:
    return bit if condition else 0


@dataclass(frozen=True)
class StatusFlags:
    """Everything both status words report, computed once per step by the drive."""

    state: State
    mode: int
    motion_enabled: bool = False  # R05 Ien_st
    stopping: bool = False  # R05 Stp_st: a stop ramp is running
    latched: bool = False  # R05 Ltc_st, 0x6041 bit 14
    latch_input: bool = False  # 0x6041 bit 8
    target_reached: bool = False  # 0x6041 bit 10
    limit_active: bool = False  # 0x6041 bit 11
    set_point_ready: bool = False  # R05 sp_rdy
    set_point_ack: bool = False  # 0x6041 bit 12 (pp)
    end_of_job: bool = False  # R05 EOJ
    following_error: bool = False  # R05 bit 7 (positioner), 0x6041 bit 13 (pp)
    zero_speed: bool = False  # R05 bit 7 (velocity), 0x6041 bit 12 (pv)
    homing_attained: bool = False
    homing_error: bool = False
    ip_active: bool = False
    axis_started: bool = False
    save_done: bool = False
    load_done: bool = False
    velocity_forced_zero: bool = False  # 0x6041 bit 15


def register_status(f: StatusFlags) -> int:
    """R05 (quick reference bit table)."""
    sw = _bit(f.state.in_torque, 0x01) | _bit(f.motion_enabled, 0x02)
    sw |= _bit(f.stopping, 0x04) | _bit(f.state in (State.FAULT, State.FAULT_REACTION_ACTIVE),
                                        0x08)
    sw |= _bit(f.latched, 0x10)
    if f.mode in POSITIONER:
        sw |= _bit(f.set_point_ready, BIT5) | _bit(f.end_of_job, BIT6)
        sw |= _bit(f.following_error, BIT7)
    elif f.mode in VELOCITY:
        sw |= _bit(f.zero_speed, BIT7)
    elif f.mode in HOMING:
        sw |= _bit(f.homing_attained, BIT6) | _bit(f.homing_error, BIT7)
    elif f.mode in INTERPOLATOR:
        sw |= _bit(f.ip_active, BIT5)
    elif f.mode in ELECTRONIC_AXIS:
        sw |= _bit(f.axis_started, BIT6)
    elif f.mode in SAVE_LOAD:
        sw |= _bit(f.save_done, BIT5) | _bit(f.load_done, BIT6)
    return sw


def cia402_status(f: StatusFlags) -> int:
    """0x6041 (DSP 402 plus the manufacturer bits 8, 14, 15 of ch. 4)."""
    sw = ds402.STATE_BITS[f.state] | ds402.SW_REMOTE
    sw |= _bit(f.state in ds402.VOLTAGE_ENABLED_STATES, ds402.SW_VOLTAGE_ENABLED)
    sw |= _bit(f.latch_input, ds402.SW_LATCH_INPUT) | _bit(f.latched, ds402.SW_LATCHED)
    sw |= _bit(f.target_reached, ds402.SW_TARGET_REACHED)
    sw |= _bit(f.limit_active, ds402.SW_INTERNAL_LIMIT)
    sw |= _bit(f.velocity_forced_zero, ds402.SW_VELOCITY_FORCED_ZERO)
    if f.mode in POSITIONER:
        sw |= _bit(f.set_point_ack, ds402.SW_MODE_12) | _bit(f.following_error,
                                                              ds402.SW_MODE_13)
    elif f.mode in VELOCITY:
        sw |= _bit(f.zero_speed, ds402.SW_MODE_12)
    elif f.mode in HOMING:
        sw |= _bit(f.homing_attained, ds402.SW_MODE_12) | _bit(f.homing_error,
                                                                ds402.SW_MODE_13)
    elif f.mode in INTERPOLATOR:
        sw |= _bit(f.ip_active, ds402.SW_MODE_12)
    elif f.mode in ELECTRONIC_AXIS:
        sw |= _bit(f.axis_started, ds402.SW_MODE_12)
    return sw
