"""What a flash save keeps, and how it is laid out in the FlashStore blob.

Seed 004 ch. 2 "Salvataggio su flash di parametri e registri" (mode -50 + control word 0x20,
or 0x0011 at 0x3802; only with the axis not in torque; the drive does not answer on Modbus for
the few seconds of the save) and ch. 4 "Salvataggio su flash" (0x1010:1 = 0x65766173; a
request with the motor enabled completes when it is disabled; keypad parameters and the listed
objects are kept). The blob is JSON: parameters by name, registers by number, so a stored
drive stays readable and a bad blob is detected instead of half-applied.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass

from devices.servo.errors import AccessError
from devices.servo.parameters import PARAMETER_BY_NAME, PARAMETERS
from devices.servo.registers import REGISTERS, R

FORMAT = "fieldrig-servo/1"
SAVE_DURATION_US = 3_000_000  # "operazione della durata di qualche secondo", reply < 5 s
SAVE_SIGNATURE = 0x65766173  # "save" in ASCII, little endian (0x1010:1, ch. 4)
COE_SAVE_VALUE = 0x11  # 0x2007 (ch. 5), like 0x3802 on Modbus (ch. 2)

# R00 is printed "Si" but a control word restored at power-up would command torque on its own
# (docs/servo-drive.md §Flash): it is not kept.
NOT_PERSISTED = frozenset({int(R.CONTROL_WORD)})
SAVED_REGISTERS = tuple(n for n, spec in sorted(REGISTERS.items())
                        if spec.saveable and n not in NOT_PERSISTED)
SAVED_PARAMETERS = tuple(a for a, spec in sorted(PARAMETERS.items()) if spec.saveable)


class FlashContentError(ValueError):
    """The stored blob is not a drive image this model wrote (the drive raises alarm 9)."""


@dataclass(frozen=True)
class Image:
    parameters: dict[int, int]  # by address
    registers: dict[int, int]  # by number


def encode(parameters: Mapping[int, int], registers: Mapping[int, int]) -> bytes:
    doc = {
        "format": FORMAT,
        "parameters": {PARAMETERS[a].name: parameters[a] for a in SAVED_PARAMETERS},
        "registers": {f"R{n:02d}": registers[n] for n in SAVED_REGISTERS},
    }
    return json.dumps(doc, indent=1, sort_keys=True).encode("utf-8")


def decode(blob: bytes) -> Image:
    """Parse and check every value; any problem rejects the whole image."""
    try:
        doc = json.loads(blob.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FlashContentError(f"not a drive image: {exc}") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise FlashContentError("not a drive image (format tag missing or unknown)")
    params, regs = doc.get("parameters"), doc.get("registers")
    if not isinstance(params, dict) or not isinstance(regs, dict):
        raise FlashContentError("drive image without parameters or registers")
    image = Image({}, {})
    try:
        for name, value in params.items():
            spec = PARAMETER_BY_NAME.get(name)
            if spec is None or not spec.saveable:
                raise FlashContentError(f"unknown parameter {name!r} in the image")
            image.parameters[spec.address] = spec.check(value)
        for key, value in regs.items():
            number = int(key[1:]) if key.startswith("R") and key[1:].isdigit() else -1
            if number not in SAVED_REGISTERS:
                raise FlashContentError(f"register {key!r} is not saved to flash")
            image.registers[number] = REGISTERS[number].check(value)
    except AccessError as exc:
        raise FlashContentError(f"bad value in the image: {exc}") from None
    return image
