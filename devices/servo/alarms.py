"""Alarm codes of the drive, their effect and the 0x603F error codes, as data.

Sources: seed 004 ch. 3 "Codici di Allarme" (codes 1-10, 13-16, 22-26 with meaning and action),
ch. 5 "Codici allarmi specifici" (0x603F table; adds 11, 12, 20, 21 and the fieldbus codes
30-35 for EtherCAT) and ch. 6 (30-34 for Profinet, with "Resettabile" NO for 30-33).
An action printed "Asse rilasciato immediatamente" releases the axis at once (torque off);
where the action is blank or "-" the model stops the axis on the emergency ramp before torque
goes off (docs/servo-drive.md §Alarms).
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from devices.canopen.emcy import ErrorHistory

GENERIC_ERROR_CODE = 0x1000  # DS402 "generic error", for the codes ch. 5 prints "-" or omits


class Effect(enum.Enum):
    RELEASE = "axis released immediately"
    STOP = "none printed: stop on the emergency ramp, then torque off"


# The effect in a trainee's words (the Codes tab, app/decoder.py; docs/servo-drive.md §Alarms).
EFFECT_TEXT: dict[Effect, str] = {
    Effect.RELEASE: "the axis is released at once (torque off)",
    Effect.STOP: "the axis stops on the emergency ramp, then torque goes off",
}


@dataclass(frozen=True)
class AlarmSpec:
    code: int
    name: str
    description: str
    effect: Effect
    error_code: int | None  # 0x603F sub0; None where the seed prints none
    resettable: bool = True

    @property
    def error_code_or_generic(self) -> int:
        return self.error_code if self.error_code is not None else GENERIC_ERROR_CODE

    def as_dict(self) -> dict[str, object]:
        return {"code": self.code, "name": self.name, "description": self.description,
                "effect": self.effect.value}


R, N = Effect.RELEASE, Effect.STOP
_DRIVE_ALARMS: tuple[AlarmSpec, ...] = (
    AlarmSpec(1, "IGBT", "IGBT module: overcurrent, overtemperature or short circuit", R,
              0x2340),
    AlarmSpec(2, "MOTOR_THERMAL", "motor overtemperature", N, 0x7120),
    AlarmSpec(3, "MOTOR_CURRENT", "excessive motor current", R, 0x2310),
    AlarmSpec(4, "OVERVOLTAGE", "excessive voltage on the DC power bus", R, 0x3210),
    AlarmSpec(5, "UNDERVOLTAGE", "DC power bus voltage below the minimum", N, 0x3220),
    AlarmSpec(6, "DRIVE_THERMAL", "drive overtemperature", N, 0x4310),
    AlarmSpec(7, "HARDWARE", "hardware fault (DSP processor in fault)", N, 0x5220),
    AlarmSpec(8, "POSITION_SENSOR", "position sensor (resolver or encoder) malfunction", R,
              0x7300),
    AlarmSpec(9, "FLASH", "non-volatile memory (flash) malfunction", R, 0x5500),
    AlarmSpec(10, "BRAKING_RESISTOR", "excessive braking resistor intervention", N, 0x7110),
    AlarmSpec(11, "NETWORK_COMMUNICATION", "network communication error", N, 0x7500),
    AlarmSpec(12, "HOMING_OPERATION", "error during the homing operation", N, 0x7320),
    AlarmSpec(13, "NETWORK", "network communication error", N, 0x7500),
    AlarmSpec(14, "HOMING", "homing error: homing not completed correctly", R, 0x7320),
    AlarmSpec(15, "OVERFLOW", "overflow in the positioning system", N, 0x5500),
    AlarmSpec(16, "FOLLOWING_ERROR", "maximum position following error exceeded for longer "
              "than the timeout", R, 0x8611),
    AlarmSpec(20, "LS1", "negative limit switch (LS1) reached", N, 0x8612),
    AlarmSpec(21, "LS2", "positive limit switch (LS2) reached", N, 0x8612),
    AlarmSpec(22, "ABS_ENCODER_HOMING", "absolute encoder zeroing not done", R, None),
    AlarmSpec(23, "ABS_ENCODER_ALIGNMENT", "motor alignment with the absolute encoder not done",
              R, 0x7300),
    AlarmSpec(24, "ABS_ENCODER_COMMUNICATION", "communication with the absolute encoder failed",
              R, 0x7300),
    AlarmSpec(25, "AXIS_MOVING_AT_POWER_ON", "axis found moving at power-on (absolute encoder)",
              R, 0x7300),
    AlarmSpec(26, "MODE_NOT_ALLOWED", "operating mode not compatible with an external encoder",
              R, 0x5114),
)

# Ch. 5 (EtherCAT); used for Modbus and CANopen too, whose chapters print no 30-35 table.
_FIELDBUS_ALARMS: tuple[AlarmSpec, ...] = (
    AlarmSpec(30, "INTERNAL_COMM_TIMEOUT", "drive internal communication timeout", N, None),
    AlarmSpec(31, "INTERNAL_COMM_1", "drive internal communication error 1", N, 0x7500),
    AlarmSpec(32, "INTERNAL_COMM_2", "drive internal communication error 2", N, 0x7500),
    AlarmSpec(33, "PDO_MAPPING", "PDO mapping not done correctly", N, 0x6320),
    AlarmSpec(34, "SYNC_TIMEOUT", "synchronisation timeout with the EtherCAT master", N, 0x8700),
    AlarmSpec(35, "ECAT_EEPROM", "EtherCAT EEPROM load error at start-up", N, 0x5530),
)

ECAT_EEPROM = 35

# Ch. 6 (Profinet): 30-33 not resettable, 34 resettable with control word 0x08. Its table
# prints no 0x603F code, and a Profinet drive has no 0x603F and sends no emergency (a 32-byte
# shared memory): none of these has an error code (CODED_FIELDBUSES).
_PROFINET_ALARMS: tuple[AlarmSpec, ...] = (
    AlarmSpec(30, "INTERNAL_COMM_TIMEOUT", "drive internal communication timeout", N, None,
              resettable=False),
    AlarmSpec(31, "PROFINET_INIT_1", "Profinet interface initialisation error, phase 1", N,
              None, resettable=False),
    AlarmSpec(32, "PROFINET_INIT_2", "Profinet interface initialisation error, phase 2", N,
              None, resettable=False),
    AlarmSpec(33, "PROFINET_NOT_STARTED", "Profinet fieldbus did not start correctly", N,
              None, resettable=False),
    AlarmSpec(34, "PROFINET_SYNC_TIMEOUT", "synchronisation timeout with the Profinet master", N,
              None),
)
# The fieldbuses on which the drive has 0x603F and sends emergencies (ch. 4 CANopen, ch. 5
# CoE): an emergency or a 0x603F code is read against their tables only.
CODED_FIELDBUSES: tuple[str, ...] = ("canopen", "ethercat")
del R, N

DRIVE_ALARMS: dict[int, AlarmSpec] = {a.code: a for a in _DRIVE_ALARMS}


# How a master of each fieldbus resets the alarms (the drive log's hint). Modbus: Alm_rst, R00
# bit 3 (ch. 1, ch. 2 "valore: 0x0008"). CANopen and CoE: 0x80 on 0x6040, bit 7 (ch. 4
# examples "0x0080"; ch. 5 "Reset allarmi": "scrittura 0x80 su oggetto 0x6040"). Profinet:
# "scrivendo il codice 0x08 nella Control Word" (ch. 6 "Reset allarmi"), which is R00: the
# ch. 6 example writes 0x0008, 0x0003, 0x0043 to "Registro 0 control_word".
RESET_HINT: dict[str, str] = {
    "modbus": "R00 bit 3",
    "canopen": "0x6040 = 0x80 (bit 7)",
    "ethercat": "0x6040 = 0x80 (bit 7)",
    "profinet": "Control Word = 0x08 (R00 bit 3)",
}
RESET_HINT_ANY = "R00 bit 3 or 0x6040 bit 7"  # c9 names no fieldbus: both views are there
# An alarm no reset bit clears: Profinet 30-33 ("Resettabile" NO, ch. 6) and, on EtherCAT, 35.
POWER_CYCLE_HINT = "a power cycle: switch the drive off and on"


def reset_hint(fieldbus: str, spec: AlarmSpec) -> str:
    """How the alarm is reset on this fieldbus, in the drive log's words."""
    if not spec.resettable:
        return POWER_CYCLE_HINT
    return RESET_HINT.get(fieldbus, RESET_HINT_ANY)

_TABLES: dict[str, dict[int, AlarmSpec]] = {}


def alarm_table(fieldbus: str) -> dict[int, AlarmSpec]:
    """Every alarm the drive can raise with the given fieldbus (c9 latched at power-up).

    Built once per fieldbus and shared (read every step by the bus adapters): do not modify."""
    table = _TABLES.get(fieldbus)
    if table is None:
        bus = _PROFINET_ALARMS if fieldbus == "profinet" else _FIELDBUS_ALARMS
        table = {**DRIVE_ALARMS, **{a.code: a for a in bus}}
        if fieldbus == "ethercat":
            # 35 takes the CoE slave to INIT + 0x0051 (docs/ethercat-coe.md): no mailbox, no
            # process data, so the ch. 5 reset ("scrittura 0x80 su oggetto 0x6040") cannot
            # reach the drive, and the EEPROM loads at start-up only: a power cycle clears it.
            table[ECAT_EEPROM] = replace(table[ECAT_EEPROM], resettable=False)
        _TABLES[fieldbus] = table
    return table


def alarm_in_emergency(code: int, data: bytes, fieldbus: str = "canopen") -> AlarmSpec | None:
    """The drive alarm an emergency of the drive reports, or None (an error reset, the node's
    own life guard or PDO error): the first manufacturer byte is the alarm number
    (devices/coe/emergency.py) and the error code that alarm's 0x603F code (ch. 5)."""
    spec = alarm_table(fieldbus).get(data[0]) if data else None
    if spec is None or spec.error_code_or_generic != code:
        return None
    return spec


def error_field_text(entry: int, table: Mapping[int, AlarmSpec]) -> str:
    """0x1003:1 in words: "0x00108611 = alarm 16 FOLLOWING_ERROR, code 0x8611". The alarm
    number sits in the upper word in hex while the display and the manuals count alarms in
    decimal, so the bare word reads as "alarm 10" to a trainee (docs/canopen.md)."""
    word = f"0x{entry:08X}"
    if entry == 0:
        return f"{word} = empty"
    code, number = ErrorHistory.fields(entry)
    if number == 0:  # the node's own codes (life guard, PDO length) carry no alarm
        return f"{word} = code 0x{code:04X}, no drive alarm (the node's own emergency)"
    spec = table.get(number)
    name = spec.name if spec is not None else "(not in the drive's table)"
    return f"{word} = alarm {number} {name}, code 0x{code:04X}"


def lookup(fieldbus: str, key: int | str) -> AlarmSpec:
    """An alarm by code (16, "16") or name ("FOLLOWING_ERROR"), or KeyError with the choices."""
    table = alarm_table(fieldbus)
    if isinstance(key, str):
        text = key.strip()
        if text.isdigit():
            key = int(text)
        else:
            for spec in table.values():
                if spec.name == text.upper():
                    return spec
            raise KeyError(f"no alarm named {key!r}")
    if key not in table:
        raise KeyError(f"no alarm {key} (codes: {', '.join(str(c) for c in sorted(table))})")
    return table[key]


@dataclass(slots=True)  # slots: read every tick of a drive, as Plant's (plant.py)
class AlarmBank:
    """Latched alarms in the order they came, and the causes still present.

    A cause is what keeps an alarm from being reset: an injected fault until it is cleared, or a
    condition the model sees (e.g. a flash write that failed). Event alarms (following error,
    limit switch, homing error) have no lasting cause once the axis is released. An injected
    cause is a fault of the hardware: it outlasts a power cycle (:meth:`after_power_cycle`).
    """

    latched: list[int]
    causes: set[int]
    changes: int = 0  # counts every change: a drive skipping still steps sees one (stillness.py)
    injected: set[int] = field(default_factory=set)  # causes from inject_alarm, not cleared

    @classmethod
    def empty(cls) -> AlarmBank:
        return cls([], set())

    def after_power_cycle(self) -> list[int]:
        """The injected causes still present, in the order their alarms came: the drive finds
        them again at power-up (the CoE slave's mapping cause goes with its mapping)."""
        return [c for c in self.latched if c in self.causes and c in self.injected]

    def injected_causes(self) -> list[int]:
        """The injected causes not cleared yet, in the order their alarms came."""
        return [c for c in self.latched if c in self.injected] + sorted(
            c for c in self.injected if c not in self.latched)

    @property
    def active(self) -> int:
        """alarm_code R46: the first alarm still latched, 0 when none."""
        return self.latched[0] if self.latched else 0

    def latch(self, code: int, lasting_cause: bool, injected: bool = False) -> bool:
        """Latch an alarm; True when it was not latched before."""
        self.changes += 1
        if lasting_cause:
            self.causes.add(code)
        if injected:
            self.injected.add(code)
        if code in self.latched:
            return False
        self.latched.append(code)
        return True

    def remove_cause(self, code: int) -> None:
        """clear_alarm: the instructor takes the cause away, injected or not."""
        self.changes += 1
        self.causes.discard(code)
        self.injected.discard(code)

    def condition_gone(self, code: int) -> None:
        """The model no longer sees the condition it raised ``code`` for (the CoE slave's valid
        mapping at PREOP -> SAFEOP): its own cause goes, an injected one stands until
        clear_alarm, or a trainee could reset what the instructor injected."""
        if code in self.injected:
            return
        self.changes += 1
        self.causes.discard(code)

    def reset(self, table: dict[int, AlarmSpec]) -> list[int]:
        """Alarm reset: drop the resettable alarms whose cause is gone; return them."""
        self.changes += 1
        cleared = [c for c in self.latched if c not in self.causes and table[c].resettable]
        self.latched = [c for c in self.latched if c not in cleared]
        return cleared
