"""What a Codes tab reading is, and the readings of protocol codes no device table holds.

:class:`Meaning` and the families are shared by :mod:`app.decoder` (the device tables) and
the two protocol readers here: a Modbus exception response (seed 004 ch. 2 "Eccezioni"; the
exception names sit with the drive's Modbus layer, ``app.modbus.pdu``) and the AL status
register values of seed 000 §7.7's failed-transition line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from app.modbus.pdu import (
    EXCEPTION_FLAG,
    EXCEPTION_NAMES,
    ILLEGAL_DATA_ADDRESS,
    IMPLEMENTED_FUNCTIONS,
)
from devices.ethercat import AL_STATUS_ERROR_FLAG, AlState
from devices.events import fmt_hex

# Families: which device (or protocol layer) a reading belongs to.
ETHERCAT = "EtherCAT AL status"
FASTCAT = "FastCAT"
SERVO = "Servo drive"
TRSCAT = "TRS-CAT"
CPX = "CPX-E-EC"
CANOPEN = "CANopen (DS 301)"
SDO = "SDO abort"
DIAG = "Diagnosis message (0x10F3)"
MODBUS = "Modbus exception"


@dataclass(frozen=True)
class Meaning:
    family: str  # which device or protocol layer reads the code this way
    title: str  # what the code is, with its value: "AL status code 0x8204"
    text: str  # the plain-language meaning
    source: str  # the seed section (or standard) the table comes from


class DecodeError(ValueError):
    """The text is not a code, a frame or a name the tables know."""


_AL_STATUS_PAIR = re.compile(r"AL Status\s*'0x([0-9A-Fa-f]{1,4})'\s*read and\s*"
                             r"'0x([0-9A-Fa-f]{1,4})'\s*expected")


def register_value(value: int) -> str:
    try:
        state = AlState(value & ~AL_STATUS_ERROR_FLAG & 0x0F).name
    except ValueError:
        state = "no ESM state"
    flag = " with the error flag" if value & AL_STATUS_ERROR_FLAG else ""
    return f"{fmt_hex(value, 4)} = {state}{flag}"


def al_status_registers(text: str) -> list[Meaning]:
    """§7.7's failed transition also names two AL status *register* values (0x0130): the
    state read and the state expected; bit 4 is the error flag."""
    pair = _AL_STATUS_PAIR.search(text)
    if pair is None:
        return []
    read, expected = (int(g, 16) for g in pair.groups())
    return [Meaning(ETHERCAT, "AL status register (0x0130) read and expected",
                    f"Read {register_value(read)}, expected {register_value(expected)}: the "
                    "slave did not reach the state; the AL status code says why.",
                    "seed 000 §7.7")]


def modbus_exception(function: int | None, code: int) -> Meaning:
    """Seed 004 ch. 2 "Eccezioni": the drive answers 02 only and drops any other bad request;
    "Codici funzione": it implements 03, 06 and 16 only, so it drops a request of any other
    function too, and no exception to one comes from it."""
    name = EXCEPTION_NAMES.get(code)
    if name is None:
        raise DecodeError(f"Modbus exception {code:02X} is not a Modbus exception code "
                          f"({', '.join(f'{c:02X}' for c in EXCEPTION_NAMES)})")
    if function is not None and function not in IMPLEMENTED_FUNCTIONS:
        implemented = ", ".join(f"{fc:02d}" for fc in IMPLEMENTED_FUNCTIONS[:-1])
        text = (f"the drive never sends it: it implements functions {implemented} and "
                f"{IMPLEMENTED_FUNCTIONS[-1]:02d} only and drops a request of function "
                f"{fmt_hex(function, 2)} without a reply; another server or a gateway sent "
                "this")
    elif code == ILLEGAL_DATA_ADDRESS:
        text = ("the address names nothing on the drive (no parameter or register there): "
                "the only exception the drive answers")
    else:
        text = ("the drive never sends it: it answers 02 only and drops any other faulty "
                "request without a reply; another server or a gateway sent this")
    title = ("Modbus exception response" if function is None else
             f"Modbus exception response to function {fmt_hex(function, 2)} "
             f"({fmt_hex(function | EXCEPTION_FLAG, 2)})")
    return Meaning(MODBUS, title, f"Exception {code:02X} {name}: {text}.",
                   "seed 004 ch. 2 Eccezioni")
