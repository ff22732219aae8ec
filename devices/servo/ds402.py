"""The CiA 402 (DSP 402 v1.1) drive state machine as data, and the 0x6040 / 0x6041 bits.

Seed 004 ch. 4 refers to DSP 402 for the state machine and prints what is manufacturer
specific: controlword bits 11, 12, 14 and statusword bits 8, 14, 15 ("Descrizione degli oggetti
del Device profile"), homing on statusword bits 12/13, the enable sequence 0x0000, 0x0080,
0x0000, 0x0006, 0x0007, 0x000F, "release" 0x0002 and, after a save, 0x0006 -> bit 0 = 1
(Ready to switch on). Everything that moves the state lives in :data:`TRANSITIONS`, keyed by
(state, command); the numbers are the standard's transition numbers.
"""

from __future__ import annotations

import enum


class State(enum.Enum):
    NOT_READY_TO_SWITCH_ON = "Not ready to switch on"
    SWITCH_ON_DISABLED = "Switch on disabled"
    READY_TO_SWITCH_ON = "Ready to switch on"
    SWITCHED_ON = "Switched on"
    OPERATION_ENABLED = "Operation enabled"
    QUICK_STOP_ACTIVE = "Quick stop active"
    FAULT_REACTION_ACTIVE = "Fault reaction active"
    FAULT = "Fault"

    @property
    def label(self) -> str:
        return self.value

    @property
    def in_torque(self) -> bool:
        """The motor is powered and controlled (the register view's Ten_st)."""
        return self in _IN_TORQUE_ORDERED  # a tuple: compared by identity, no enum hashing


_IN_TORQUE_ORDERED = (State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE,
                      State.FAULT_REACTION_ACTIVE)
IN_TORQUE = frozenset(_IN_TORQUE_ORDERED)


class Command(enum.Enum):
    """Controlword commands (bits 0-3 and 7) and the drive's own internal events."""

    SHUTDOWN = "shutdown"
    SWITCH_ON = "switch on"  # also "disable operation": the same bits 0111
    ENABLE_OPERATION = "enable operation"
    DISABLE_VOLTAGE = "disable voltage"
    QUICK_STOP = "quick stop"
    FAULT_RESET = "fault reset"  # rising edge of bit 7
    # internal events
    SELF_TEST_DONE = "self test done"
    STANDSTILL = "standstill"
    FAULT = "fault"
    FAULT_REACTION_DONE = "fault reaction done"
    TORQUE_LOST = "TEN input low"


INTERNAL = frozenset({Command.SELF_TEST_DONE, Command.STANDSTILL, Command.FAULT,
                      Command.FAULT_REACTION_DONE, Command.TORQUE_LOST})

S = State
C = Command
# (state, command) -> (new state, DSP 402 transition number)
TRANSITIONS: dict[tuple[State, Command], tuple[State, int]] = {
    (S.NOT_READY_TO_SWITCH_ON, C.SELF_TEST_DONE): (S.SWITCH_ON_DISABLED, 1),
    (S.SWITCH_ON_DISABLED, C.SHUTDOWN): (S.READY_TO_SWITCH_ON, 2),
    (S.READY_TO_SWITCH_ON, C.SWITCH_ON): (S.SWITCHED_ON, 3),
    (S.READY_TO_SWITCH_ON, C.ENABLE_OPERATION): (S.SWITCHED_ON, 3),  # then 4 (0x000F)
    (S.SWITCHED_ON, C.ENABLE_OPERATION): (S.OPERATION_ENABLED, 4),
    (S.OPERATION_ENABLED, C.SWITCH_ON): (S.SWITCHED_ON, 5),  # disable operation
    (S.OPERATION_ENABLED, C.TORQUE_LOST): (S.SWITCHED_ON, 5),  # hardware TEN went low
    (S.SWITCHED_ON, C.SHUTDOWN): (S.READY_TO_SWITCH_ON, 6),
    (S.READY_TO_SWITCH_ON, C.DISABLE_VOLTAGE): (S.SWITCH_ON_DISABLED, 7),
    (S.READY_TO_SWITCH_ON, C.QUICK_STOP): (S.SWITCH_ON_DISABLED, 7),
    (S.OPERATION_ENABLED, C.SHUTDOWN): (S.READY_TO_SWITCH_ON, 8),
    (S.OPERATION_ENABLED, C.DISABLE_VOLTAGE): (S.SWITCH_ON_DISABLED, 9),
    (S.SWITCHED_ON, C.DISABLE_VOLTAGE): (S.SWITCH_ON_DISABLED, 10),
    (S.SWITCHED_ON, C.QUICK_STOP): (S.SWITCH_ON_DISABLED, 10),
    (S.OPERATION_ENABLED, C.QUICK_STOP): (S.QUICK_STOP_ACTIVE, 11),
    (S.QUICK_STOP_ACTIVE, C.STANDSTILL): (S.SWITCH_ON_DISABLED, 12),  # quick stop option 2
    (S.QUICK_STOP_ACTIVE, C.DISABLE_VOLTAGE): (S.SWITCH_ON_DISABLED, 12),
    (S.QUICK_STOP_ACTIVE, C.TORQUE_LOST): (S.SWITCH_ON_DISABLED, 12),
    **{(s, C.FAULT): (S.FAULT_REACTION_ACTIVE, 13)
       for s in State if s not in (S.FAULT_REACTION_ACTIVE, S.FAULT)},
    (S.FAULT_REACTION_ACTIVE, C.FAULT_REACTION_DONE): (S.FAULT, 14),
    (S.FAULT, C.FAULT_RESET): (S.SWITCH_ON_DISABLED, 15),
}
del S, C


class InvalidTransition(LookupError):
    def __init__(self, state: State, command: Command) -> None:
        super().__init__(f"CiA 402: no transition from '{state.label}' on '{command.value}'")


def next_state(state: State, command: Command) -> tuple[State, int]:
    found = TRANSITIONS.get((state, command))
    if found is None:
        raise InvalidTransition(state, command)
    return found


# ---- controlword 0x6040 ------------------------------------------------------------------
CW_SWITCH_ON = 0x0001
CW_ENABLE_VOLTAGE = 0x0002
CW_QUICK_STOP = 0x0004  # active low
CW_ENABLE_OPERATION = 0x0008
CW_NEW_SET_POINT = 0x0010  # pp: new set-point; hm: homing start; ip: enable interpolation
CW_CHANGE_IMMEDIATELY = 0x0020  # pp
CW_RELATIVE = 0x0040  # pp: target is relative
CW_FAULT_RESET = 0x0080
CW_HALT = 0x0100
CW_AXIS_START = 0x0800  # bit 11, manufacturer: electronic-axis start
CW_MASTER_SPEED = 0x1000  # bit 12, manufacturer: 0x6069 returns the master speed (incr/ms)
CW_LATCH_RESET = 0x4000  # bit 14, manufacturer: 0 -> 1 clears statusword bit 14

CONTROLWORD_BITS: dict[int, str] = {
    0: "switch on", 1: "enable voltage", 2: "quick stop (active low)", 3: "enable operation",
    4: "operation mode specific (new set-point / homing start / interpolation)",
    5: "change set immediately", 6: "absolute / relative", 7: "fault reset", 8: "halt",
    11: "electronic axis start", 12: "0x6069 = master speed", 14: "latch update reset",
}


def decode(controlword: int) -> Command | None:
    """The level command of a controlword (bit 7 held high commands nothing: DSP 402)."""
    if controlword & CW_FAULT_RESET:
        return None
    if not controlword & CW_ENABLE_VOLTAGE:
        return Command.DISABLE_VOLTAGE
    if not controlword & CW_QUICK_STOP:
        return Command.QUICK_STOP
    if not controlword & CW_SWITCH_ON:
        return Command.SHUTDOWN
    if controlword & CW_ENABLE_OPERATION:
        return Command.ENABLE_OPERATION
    return Command.SWITCH_ON


# The controlword a master writes for each command (DSP 402; seed 004 ch. 4 enable sequence
# 0x0006, 0x0007, 0x000F, "release" 0x0002; bit 7's rising edge resets a fault).
COMMAND_WORDS: dict[Command, int] = {
    Command.SHUTDOWN: 0x0006,
    Command.SWITCH_ON: 0x0007,
    Command.ENABLE_OPERATION: 0x000F,
    Command.DISABLE_VOLTAGE: 0x0000,
    Command.QUICK_STOP: 0x0002,
    Command.FAULT_RESET: 0x0080,
}


# ---- statusword 0x6041 -------------------------------------------------------------------
# Bits 0-3, 5, 6 of each state (DSP 402 statusword table; "x" bits as 0). Bit 4 "voltage
# enabled" is added from Switched on ("high voltage has been applied"; in Ready to switch on it
# only "may be": seed 004 ch. 5's TwinCAT screen reads 0x0621 there, bit 4 clear).
STATE_BITS: dict[State, int] = {
    State.NOT_READY_TO_SWITCH_ON: 0x0000,
    State.SWITCH_ON_DISABLED: 0x0040,
    State.READY_TO_SWITCH_ON: 0x0021,
    State.SWITCHED_ON: 0x0023,
    State.OPERATION_ENABLED: 0x0027,
    State.QUICK_STOP_ACTIVE: 0x0007,
    State.FAULT_REACTION_ACTIVE: 0x000F,
    State.FAULT: 0x0008,
}
VOLTAGE_ENABLED_STATES = frozenset({State.SWITCHED_ON, State.OPERATION_ENABLED,
                                    State.QUICK_STOP_ACTIVE})

SW_VOLTAGE_ENABLED = 0x0010
SW_WARNING = 0x0080
SW_LATCH_INPUT = 0x0100  # bit 8, manufacturer: latching input status
SW_REMOTE = 0x0200
SW_TARGET_REACHED = 0x0400
SW_INTERNAL_LIMIT = 0x0800
SW_MODE_12 = 0x1000  # pp: set-point acknowledge; pv: speed = 0; hm: attained; ip: active
SW_MODE_13 = 0x2000  # pp: following error; hm: homing error
SW_LATCHED = 0x4000  # bit 14, manufacturer: new latched position (0x2001 / 0x2004)
SW_VELOCITY_FORCED_ZERO = 0x8000  # bit 15, manufacturer: TEN or IEN low

STATUSWORD_BITS: dict[int, str] = {
    0: "ready to switch on", 1: "switched on", 2: "operation enabled", 3: "fault",
    4: "voltage enabled", 5: "quick stop", 6: "switch on disabled", 7: "warning",
    8: "latching input", 9: "remote", 10: "target reached", 11: "internal limit active",
    12: "mode specific 12", 13: "mode specific 13", 14: "latched position update",
    15: "target velocity forced to zero",
}
# The same bits in short words (a narrow grid cell; the names above are its tooltip).
STATUSWORD_SHORT: dict[int, str] = {
    0: "ready to switch on", 1: "switched on", 2: "operation enabled", 3: "fault",
    4: "voltage enabled", 5: "quick stop", 6: "switch on disabled", 7: "warning",
    8: "latch input", 9: "remote", 10: "target reached", 11: "limit active",
    12: "mode specific", 13: "mode specific", 14: "latched position",
    15: "velocity forced 0",
}
STATUSWORD_ERROR_BITS = frozenset({3, 7, 11})  # fault, warning, internal limit active


def state_of(statusword: int) -> State:
    """The state a statusword shows (the DSP 402 decode masks), for tests and masters."""
    low = statusword & 0x006F
    for state, bits in STATE_BITS.items():
        mask = 0x004F if state in (State.NOT_READY_TO_SWITCH_ON, State.SWITCH_ON_DISABLED,
                                   State.FAULT_REACTION_ACTIVE, State.FAULT) else 0x006F
        if low & mask == bits & mask:
            return state
    raise ValueError(f"statusword 0x{statusword:04X} shows no CiA 402 state")
