"""The Servo drive tab's option tables and their hints: modes, registers, parameters, fieldbuses
and alarms as the dropdowns list them, and each option's whole label, range, access and Modbus
address (seed 004 ch. 1, ch. 2; ch. 3, ch. 5, ch. 6 for the alarms)."""

from __future__ import annotations

from typing import Any

from devices.servo.alarms import alarm_table
from devices.servo.flashsave import SAVED_REGISTERS
from devices.servo.homing import HOMING_ALARM, METHODS
from devices.servo.modbus_map import NORMAL, SIEMENS, parameter_address, register_address
from devices.servo.parameters import (
    C9_BY_FIELDBUS,
    FIELDBUS_BY_C9,
    FIELDBUS_NAMES,
    PARAMETERS,
    node_range,
)
from devices.servo.registers import MODE_NAMES, REGISTERS, R, RegisterSpec

MODE_OPTIONS = tuple(f"{mode} {name}" for mode, name in MODE_NAMES.items())
REGISTER_OPTIONS = tuple(f"R{n:02d} {spec.name}" for n, spec in sorted(REGISTERS.items()))
PARAMETER_OPTIONS = tuple(f"{spec.name} {spec.meaning}" for spec in PARAMETERS.values())
FIELDBUS_OPTIONS = tuple(f"{code} {FIELDBUS_NAMES[name]}"
                         for code, name in FIELDBUS_BY_C9.items())


def alarm_details(fieldbus: str) -> dict[str, str]:
    """``"16 FOLLOWING_ERROR"`` -> ``"16 FOLLOWING_ERROR: maximum position ..."`` for every
    alarm of the drive with this fieldbus (ch. 3, ch. 5; ch. 6 for Profinet), in code order:
    the list shows the labels, the box's hint the description (:class:`DetailHint`)."""
    alarms = sorted(alarm_table(fieldbus).values(), key=lambda a: a.code)
    return {f"{a.code} {a.name}": f"{a.code} {a.name}: {a.description}" for a in alarms}


def modbus_words(address: int, address_map: str) -> str:
    """A Modbus address as the manual writes it under the map: hex in the normal one (ch. 1),
    decimal and hex with the map named in the Siemens one (ch. 2: "40001 + 1 = 40002 =
    0x9C42")."""
    if address_map == SIEMENS:
        return f"Modbus {address} = 0x{address:04X} (e3 = 9, Siemens map)"
    return f"Modbus 0x{address:04X}"


def register_details(address_map: str = NORMAL) -> dict[str, str]:
    """``"R24 master_encoder_increments"`` -> its range, access and Modbus address under the
    drive's map (ch. 1 "Registri", ch. 2 "Estensione della mappatura"): the box holds about
    25 characters, so the hint carries the label whole."""
    out = {}
    for n, spec in sorted(REGISTERS.items()):
        # what a save keeps, not the "Si" column: R00 is printed "Si" and is not kept
        access = ("read only" if not spec.writable
                  else "kept by Save to flash" if n in SAVED_REGISTERS else "not saved")
        where = modbus_words(register_address(n, address_map), address_map)
        values = _register_values(spec) + (_homing_methods() if n == R.HOMING_METHOD else "")
        out[f"R{n:02d} {spec.name}"] = f"R{n:02d} {spec.name}: {values}, {access}; {where}"
    return out


def _homing_methods() -> str:
    """R18 takes 0..255, but Home with a method the drive has not is alarm 14 (docs/servo-
    drive.md "Homing"): the hint names the ones it runs, runs of numbers joined ("1-4")."""
    runs: list[list[int]] = []
    for number in sorted(METHODS):
        if runs and number == runs[-1][-1] + 1:
            runs[-1].append(number)
        else:
            runs.append([number])
    methods = ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 1 else str(r[0]) for r in runs)
    name = alarm_table("modbus")[HOMING_ALARM].name
    return f" (Home runs methods {methods}; any other: alarm {HOMING_ALARM} {name})"


def _register_values(spec: RegisterSpec) -> str:
    """The values the drive takes: a closed set of codes (R01's modes, R27's profiles) is
    named, as the drive refuses any other inside the printed range."""
    printed = f"{spec.low}..{spec.high}"
    if spec.allowed is None:
        return printed
    return f"one of {', '.join(str(v) for v in spec.allowed)} (printed {printed})"


def _parameter_values(name: str, low: int, high: int) -> str:
    """c7's range narrows on Modbus: "ogni valore tra 1 e 90" with c9 = 3 (ch. 2
    "Configurazione della rete"), 1..99 otherwise (ch. 4)."""
    if name != "c7":
        return f"{low}..{high}"
    narrower = []
    for bus, c9 in C9_BY_FIELDBUS.items():
        bus_low, bus_high = node_range(c9)
        if (bus_low, bus_high) != (low, high):
            narrower.append(f"{bus_low}..{bus_high} with c9 = {c9}, {FIELDBUS_NAMES[bus]}")
    return f"{low}..{high}" + (f" ({'; '.join(narrower)})" if narrower else "")


def parameter_details(address_map: str = NORMAL) -> dict[str, str]:
    """``"c9 operating mode / fieldbus"`` -> its range, default and Modbus address under the
    drive's map (ch. 1 "Parametri", ch. 2), and whether it acts only at the next power-up."""
    out = {}
    for spec in PARAMETERS.values():
        unit = " %" if spec.unit == "%" else ""
        when = "; read at power-up" if spec.power_up else ""
        access = "" if spec.writable else ", read only"
        where = modbus_words(parameter_address(spec.address, address_map), address_map)
        out[f"{spec.name} {spec.meaning}"] = (
            f"{spec.name} {spec.meaning}: {_parameter_values(spec.name, spec.low, spec.high)}"
            f"{unit}, default "
            f"{spec.default}{access}{when}; {where}")
    return out


def alarm_options(fieldbus: str) -> tuple[str, ...]:
    return tuple(alarm_details(fieldbus))


def leading_int(option: str) -> int:
    """The number an option starts with: ``"-127 analog reference"`` -> -127."""
    return int(option.split(" ", 1)[0])


def register_of(option: str) -> int:
    return int(option.split(" ", 1)[0][1:])


def register_option(n: int) -> str:
    return next(o for o in REGISTER_OPTIONS if register_of(o) == n)


def mode_option(mode: Any) -> str | None:
    return next((o for o in MODE_OPTIONS if leading_int(o) == mode), None)

