"""The CPX-E-EC's diagnosis code tables: emergency codes, error register, status bits, Text-IDs,
CPX error numbers and what physical cause raises which of them.

Seed 002 §2.5.2 (Tab. 15-17) and §2.5.3 (Tab. 20-26). CPX error numbers other than 2 (short
circuit, Tab. 16) live in the "CPX-E system description" the seed refers to and does not
include: FieldRig's numbers for them are in CPX_ERRORS and docs/cpx-e-ec.md.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from devices.bitwords import BitWords

# §2.5.3 Tab. 21: emergency error code (bytes 1, 0), after DS301 / DS401.
EMCY_NO_ERROR = 0x0000
EMCY_GENERAL = 0x1000
EMCY_OUTPUT_SHORT_CIRCUIT = 0x2320
EMCY_LOAD_DUMP = 0x2330
EMCY_INPUT_VOLTAGE_LOW = 0x3120
EMCY_OUTPUT_VOLTAGE_LOW = 0x3320
EMCY_HARDWARE = 0x5000
EMCY_CODES: dict[int, str] = {
    EMCY_NO_ERROR: "No error",
    EMCY_GENERAL: "General system error",
    EMCY_OUTPUT_SHORT_CIRCUIT: "Short circuit at the outputs",
    EMCY_LOAD_DUMP: "Load dump (wire break)",
    EMCY_INPUT_VOLTAGE_LOW: "Input voltage too low",
    EMCY_OUTPUT_VOLTAGE_LOW: "Output voltage too low",
    EMCY_HARDWARE: "Hardware error (all errors > 128)",
}
HARDWARE_ERROR_ABOVE = 128  # Tab. 21: CPX error numbers > 128 answer 0x5000

# §2.5.3 Tab. 22: error register (byte 2, object 0x1001).
REG_GENERIC = 0x01  # bit 0: set with every error
REG_CURRENT = 0x02  # bit 1: KZS (sensor supply) / KZA (outputs) short circuit, overload
REG_VOLTAGE = 0x04  # bit 2: U_OUT undervoltage, load voltage failure
REG_COMMUNICATION = 0x10  # bit 4: node guard, heartbeat (other fieldbuses only)
REG_MANUFACTURER = 0x80  # bit 7: wire break, other error
# Each bit's name and explanation as Tab. 22 prints them (the Codes tab reads a CPX-E-EC's
# 0x1001 in these words); bits 3, 5 and 6 are "-" there.
ERROR_REGISTER_BITS: dict[int, tuple[str, str]] = {
    REG_GENERIC: ("Generic Error", "set with every error"),
    REG_CURRENT: ("Current", "KZS: short circuit/overload of the sensor supply; KZA: short "
                             "circuit/overload of the outputs"),
    REG_VOLTAGE: ("Voltage", "undervoltage at the outputs (U_OUT); load voltage failure at an "
                             "output or input module"),
    REG_COMMUNICATION: ("Communication Error", "node guard, heartbeat: other fieldbuses only"),
    REG_MANUFACTURER: ("Manufacturer specific", "wire break, other error"),
}
# The same table as the views read it (the Slave tab's 0x1001 row, the Objects tab, the Codes
# tab with the explanations).
ERROR_REGISTER_WORDS = BitWords(
    {mask: name for mask, (name, _) in ERROR_REGISTER_BITS.items()},
    {mask: note for mask, (_, note) in ERROR_REGISTER_BITS.items()}, blank='"-" in Tab. 22')

# §2.5.3 Tab. 23: status bits (byte 3, object 0x1002; the same 8 bits are the status-bit
# inputs of §2.4.2). Bits 0-3 name the module type, bits 4-7 the error type.
ST_VALVE = 0x01
ST_OUTPUT = 0x02
ST_INPUT = 0x04
ST_ANALOG = 0x08
ST_UNDERVOLTAGE = 0x10
ST_SHORT_CIRCUIT = 0x20
ST_WIRE_BREAK = 0x40
ST_OTHER = 0x80
STATUS_BITS: dict[int, str] = {
    0: "Error at valve terminal", 1: "Error at output", 2: "Error at input",
    3: "Error at analog or technology module", 4: "Undervoltage",
    5: "Short circuit/overload", 6: "Wire break", 7: "Other error",
}


class DiagType(enum.IntEnum):
    """Diagnosis message type, low nibble of the message flags (Tab. 16: 2 = Error Message)."""

    INFO = 0
    WARNING = 1
    ERROR = 2


# §2.5.2 Tab. 16: the top byte of the Diag Code says what its low bytes hold.
DIAG_CODE_CPX = 0xE1  # "E1 = CPX-E error number"
DIAG_CODE_DS401 = 0xE8  # "E8 = Error Code per DS401"


def diag_code(marker: int, number: int) -> int:
    """``02 00 00 E1`` (little-endian UDINT): marker in the top byte, the number below."""
    return marker << 24 | number


# §2.5.2 Tab. 17: Text-IDs from the ESI file, and 0x3700 + n for CPX error number n.
CPX_TEXT_ID_BASE = 0x3700  # "3700h ... 37FFh = CPX error numbers 0 ... 255"
TEXT_IDENT_FAILED = 0x3800
TEXT_IDENT_SKIPPED = 0x3801
TEXT_BUS_CYCLE = 0x000F
TEXT_SM_ADDRESS = 0x0011
TEXT_SM_SIZE = 0x0012
TEXT_SM_SETTINGS = 0x0013
TEXT_IDS: dict[int, tuple[str, str]] = {  # (Russian, English) as Tab. 17 prints them
    TEXT_IDENT_FAILED: ("Не удалось выполнить идентификацию модуля",
                        "Ident check failed for configured module"),
    TEXT_IDENT_SKIPPED: ("Проверка идентификации модуля не выполнена – Контроллер не записал "
                         "объект 0xF030",
                         "Ident check skipped – PLC has not written to Object 0xF030"),
    TEXT_BUS_CYCLE: ("Не удалось рассчитать длительность цикла обращения к шине (локальный "
                     "таймер слишком медленный)",
                     "Calculate bus cycle time failed (Local timer too slow)"),
    TEXT_SM_ADDRESS: ("Недействительный адрес диспетчера синхронизации (Sync Manager)",
                      "Sync Manager invalid address"),
    TEXT_SM_SIZE: ("Недействительная величина I/O Sync Manager", "Sync Manager invalid size"),
    TEXT_SM_SETTINGS: ("Недействительная конфигурация Sync Manager",
                       "Sync Manager invalid settings"),
}


@dataclass(frozen=True)
class CpxError:
    """A CPX error number (Text-ID 0x3700 + number) and how it is reported."""

    number: int
    symbol: str
    text: str
    error_bit: int  # Tab. 23 bits 4-7
    error_class: int  # 1 simple, 2 standard diagnosis, 3 hardware: the SF flash count
    seed: str  # where the number comes from

    @property
    def text_id(self) -> int:
        return CPX_TEXT_ID_BASE + self.number


CPX_ERRORS: dict[int, CpxError] = {e.number: e for e in (
    CpxError(2, "SHORT_CIRCUIT", "Short circuit/overload", ST_SHORT_CIRCUIT, 2, "Tab. 16"),
    CpxError(3, "WIRE_BREAK", "Wire break", ST_WIRE_BREAK, 2, "FieldRig"),
    CpxError(8, "UNDERVOLTAGE", "Undervoltage", ST_UNDERVOLTAGE, 2, "FieldRig"),
    CpxError(129, "MODULE_FAILURE", "Module hardware failure", ST_OTHER, 3, "FieldRig"),
)}


# CPX error number 0 (Text-ID 0x3700): the message of a fault that has gone (FieldRig,
# docs/cpx-e-ec.md choice 20; Tab. 21's "No error").
NO_ERROR_TEXT = EMCY_CODES[EMCY_NO_ERROR]


def text_id_texts() -> dict[int, tuple[str | None, str]]:
    """Every Text-ID the bus module writes into 0x10F3, with its (Russian, English) text, as
    the ESI gives them to a configurator (§2.5.2): Tab. 17's EtherCAT ones in both languages,
    and 0x3700 + n for CPX error number 0 and those of CPX_ERRORS, in English (their Russian
    is in the system description the seed does not include)."""
    texts: dict[int, tuple[str | None, str]] = {CPX_TEXT_ID_BASE: (None, NO_ERROR_TEXT)}
    texts.update((e.text_id, (None, e.text)) for e in CPX_ERRORS.values())
    texts.update(TEXT_IDS)
    return texts


@dataclass(frozen=True)
class Cause:
    """A physical cause and the codes it is reported with (docs/cpx-e-ec.md, cause -> code)."""

    name: str
    cpx_error: int
    emcy_code: int  # Tab. 21
    register_bit: int  # Tab. 22, besides bit 0 (generic)
    module_bit: int | None = None  # Tab. 23 bits 0-3; None: from the module's kind

    @property
    def error(self) -> CpxError:
        return CPX_ERRORS[self.cpx_error]


CAUSES: dict[str, Cause] = {c.name: c for c in (
    # Tab. 22 bit 1 names both KZS (sensor supply) and KZA (outputs); Tab. 21 has one short
    # circuit code, "at the outputs": the sensor supply is an output of the module too.
    Cause("short_circuit_outputs", 2, EMCY_OUTPUT_SHORT_CIRCUIT, REG_CURRENT),
    Cause("short_circuit_sensor_supply", 2, EMCY_OUTPUT_SHORT_CIRCUIT, REG_CURRENT),
    Cause("wire_break", 3, EMCY_LOAD_DUMP, REG_MANUFACTURER),  # Tab. 21, Tab. 22 bit 7
    Cause("undervoltage_out", 8, EMCY_OUTPUT_VOLTAGE_LOW, REG_VOLTAGE),  # U_OUT
    # U_EL/SEN feeds the electronics and the sensors: "input voltage too low", reported by
    # the bus module (module 0) as an input error (the sensors lose their supply).
    Cause("undervoltage_el_sen", 8, EMCY_INPUT_VOLTAGE_LOW, REG_VOLTAGE, ST_INPUT),
    Cause("module_failure", 129, EMCY_HARDWARE, REG_MANUFACTURER),
)}


def emcy_code_for(cause: Cause) -> int:
    """Tab. 21: any CPX error number above 128 is a hardware error."""
    if cause.cpx_error > HARDWARE_ERROR_ABOVE:
        return EMCY_HARDWARE
    return cause.emcy_code
