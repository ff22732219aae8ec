"""The drive's Modbus address maps (seed 004 ch. 2 "Estensione della mappatura degli indirizzi
per PLC Siemens"; docs/modbus.md "Addresses").

Normally a parameter sits at its quick-reference address (d1 = 0x0001) and register Rn at
0x8000 + n (ch. 1). Parameter e3 = 9 moves both for Siemens PLCs: parameters at 40001 +
address, registers at 44097 + n (the text says "a partire dall'indirizzo 44096", its examples
use 44097 + n: R00 = 0xAC41, R09 = 0xAC4A; the examples' bytes win, docs/modbus.md choice 7).
e3 is read at every request, so the map follows it at once. The save command stays at 0x3802.
"""

from __future__ import annotations

from devices.servo.registers import REGISTER_BASE

E3_ADDRESS = 58  # "Parametro Eccezioni"
E3_SIEMENS_MAP = 9
SIEMENS_PARAMETER_BASE = 40001
SIEMENS_REGISTER_BASE = 44097

NORMAL = "normal"
SIEMENS = "siemens"


def active_map(e3: int) -> str:
    """The map parameter e3 selects."""
    return SIEMENS if e3 == E3_SIEMENS_MAP else NORMAL


def parameter_address(address: int, address_map: str) -> int:
    """The Modbus address of the parameter at quick-reference ``address`` under the map."""
    return SIEMENS_PARAMETER_BASE + address if address_map == SIEMENS else address


def register_address(n: int, address_map: str) -> int:
    """The Modbus address of register Rn under the map."""
    return (SIEMENS_REGISTER_BASE if address_map == SIEMENS else REGISTER_BASE) + n
