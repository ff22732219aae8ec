"""FastCAT alarm codes, the emergency data layout and the manufacturer AL status code.

The one place for: the coupler code table (seed 000 §7.5, byte 3 of the emergency data), the
module code table (§7.6, byte 2), the 5-byte emergency data of §7 (mirrored in 0x5400, §6.23),
the 0x80XX AL status code of §7.7 and which table it belongs to: only a coupler alarm takes the
ESM out of SAFEOP / OP and shows in the AL status code (:data:`ESM_ALARM_TABLES`). Symbols are
the seed's ``CO_E_`` names without the prefix, spelled as printed (``ADDRES_NOT_OK``,
``EMICY_MASTER``); descriptions are English renderings of the Italian text. The AX2 codes
0x10..0x15 have no symbol in the seed: FieldRig names them ENC1_COUNT .. ENC2_ZERO_CYCLE
(docs/fastcat-coupler.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.device import CommandError
from devices.ethercat import describe_al_status_code
from devices.events import fmt_hex
from devices.fastcat.objects import MAX_MODULES

COUPLER = "coupler"
MODULE = "module"
TABLES = (COUPLER, MODULE)
# What an alarm of each table is, in the seed's words and section: the two tables number their
# codes independently, so a reader needs the table next to the code (the State tab's Alarm row).
TABLE_WORDS = {COUPLER: "coupler alarm (§7.5)", MODULE: "module alarm (§7.6)"}

EMERGENCY_CODE = 0xFF00  # §7: "ErrorCode: 0xFF00 (device specific)"
EMERGENCY_REGISTER = 0x81  # §7: "ErrorRegister: 0x81 (device error)"
EMERGENCY_REGISTER_TEXT = "device error"  # §7's words for it (the Codes tab reads them)
EMERGENCY_DATA_LEN = 5  # §7: 5 bytes, the first 4 significant
LAST_RESETTABLE_COUPLER_CODE = 0x7F  # §7, §7.5: coupler codes above 0x7F need a resync
AL_STATUS_MANUFACTURER = 0x8000  # §7.7: "0x80XX ... allarme manufacturer"
# Tables whose alarms take the ESM to PREOP with 0x80XX and bar SAFEOP / OP while latched.
# §7.7: the manufacturer code carries "allarmi gravi generati dal coupler" (byte 0 = coupler
# code); §7: resettable alarms are reset by the Reset Fault bit "mappato nei dati scambiati
# con il coupler", which needs process data running. So a module alarm (§7.6) keeps the ESM.
ESM_ALARM_TABLES = frozenset({COUPLER})
# §7.5: byte 0 holds "l'eventuale indice del nodo al quale si riferisce l'errore". These
# coupler codes are about no node: no module at all, the master's flash, the rotary address
# (§6.19 prints 0x5400 = 0x12000000, byte 0 = 0), the coupler's own EtherCAT cable. The
# coupler raises them with byte 0 = 0 (faults.py), and an injection may not name a module.
NO_NODE_COUPLER_CODES = frozenset({0x10, 0x11, 0x12, 0x13})


@dataclass(frozen=True)
class AlarmCode:
    table: str  # COUPLER or MODULE
    code: int
    symbol: str  # without the CO_E_ prefix
    description: str
    symbol_printed: bool = True  # False: the seed prints no symbol, FieldRig named it

    @property
    def resettable(self) -> bool:
        return is_resettable(self.table, self.code)

    @property
    def names_module(self) -> bool:
        """Whether byte 0 (the module number) means anything for this code (§7.5, §7.6)."""
        return self.table == MODULE or self.code not in NO_NODE_COUPLER_CODES

    @property
    def on_coupler(self) -> bool:
        """Whether the coupler itself (no module, byte 0 = 0) is a target: §7.6's module codes
        are "segnalati dai moduli", byte 0 = the module; §7.5's all are the coupler's."""
        return self.table == COUPLER

    @property
    def label(self) -> str:
        """``coupler:0x04`` — the unambiguous way to write a code."""
        return f"{self.table}:{fmt_hex(self.code, 2)}"


def _table(table: str, rows: tuple[tuple[int, str, str], ...],
           unnamed: frozenset[int] = frozenset()) -> dict[int, AlarmCode]:
    return {code: AlarmCode(table, code, symbol, text, code not in unnamed)
            for code, symbol, text in rows}


# §7.5 "Codici d'allarme relativi al coupler" (byte 3 of the emergency data).
COUPLER_CODES: dict[int, AlarmCode] = _table(COUPLER, (
    (0x01, "MODULE_CHANGED",
     "A module of a different type from the one previously saved in flash was detected"),
    (0x02, "MODULE_NO_PRES", "Module not detected"),
    (0x03, "UNKNOWN_NODE_ANSWER", "Unknown answer command"),
    (0x04, "MISSING_NODE_ANSWER", "No answer from the node"),
    (0x05, "CRC_PDORX", "Answer to a PDORX command with a wrong CRC"),
    (0x06, "CRC_PDOSDORX", "Answer to a PDOSDORX command with a wrong CRC"),
    (0x07, "CRC_SDO_RD", "Answer to an SDORX read command with a wrong CRC"),
    (0x08, "CRC_SDO_WR", "Answer to an SDORX write command with a wrong CRC"),
    (0x09, "ADDRES_NOT_OK", "The slave refused the address setting"),
    (0x0A, "UNKNOWN_SDO_RD_ANSWER",
     "The node answered the SDORX read command with an unknown answer command"),
    (0x0B, "UNKNOWN_SDO_WR_ANSWER",
     "The node answered the SDORX write command with an unknown answer command"),
    (0x0C, "SDO_ERROR", "The node answered the SDO with an abort code"),
    (0x0D, "TMO_SDORD", "Answer timeout from the node on an SDO read"),
    (0x0E, "TMO_SDOWR", "Answer timeout from the node on an SDO write"),
    # The seed drops a word ("comunica che la non è compatibile"): read as "its firmware".
    (0x0F, "FIRMW_MAST_NOTOK",
     "The module reports that its firmware is not compatible with the master firmware version"),
    (0x10, "NO_MOD", "No module detected by the master on the bus"),
    (0x11, "SAVE_FLASH", "Master flash save error"),
    (0x12, "ADDRESS_MASTER_NOT_OK",
     "The address set with the rotary switch does not match the address assigned by the "
     "EtherCAT master. Object 0x5301 enables this check"),
    (0x13, "LINK_LOSS", "EtherCAT cable not connected"),
    (0x14, "SLOT_NOT_MATCHING",
     "The slot given by the EtherCAT master in object 0xF030.n does not match the one "
     "detected by the coupler in object 0xF050.n"),
    (0x15, "MAX_ANALOG_MODULES",
     "The master detected more than 8 analog modules on the TBUS. The eighth module is at "
     "the position given by the lowest byte"),
))

# §7.6 "Codici d'allarme relativi ai moduli" (byte 2 of the emergency data).
MODULE_CODES: dict[int, AlarmCode] = _table(MODULE, (
    (0x01, "EMICY_MASTER", "Emergency from master"),
    (0x02, "IOFAULT", "Digital output read-back fault"),
    (0x03, "ALARM_10V", "Potentiometer input supply short-circuited"),
    (0x04, "ALARM_IO_FAULT", "Analog output protection"),
    (0x05, "TIMEOUT_SYNC", "Sync signal not received"),
    (0x06, "TIMEOUT_RX", "Command from the master not received during the communication cycle"),
    (0x07, "CRC", "Message from the master received with a wrong CRC"),
    (0x08, "UNKNOWN_CMD", "Message from the master received with an unknown command"),
    (0x09, "UNKNOWN_SDO_CMD", "SDO command not recognised (neither read nor write)"),
    (0x0A, "NO_SYNC", "The module does not see the master sync signal toggle"),
    (0x0B, "TARATURA", "The module has not been calibrated"),
    (0x0C, "LOW_VOLTAGE", "Low supply voltage on the Tbus"),
    (0x0D, "BAD_GAIN", "(EnergyMeter only) Incorrect gains"),
    (0x0E, "BAD_CODEID", "(EnergyMeter only) ADE9000 chip code not recognised"),
    (0x10, "ENC1_COUNT", "AX2 module encoder 1 count alarm"),
    (0x11, "ENC2_COUNT", "AX2 module encoder 2 count alarm"),
    (0x12, "ENC1_SIGNAL", "AX2 module encoder 1 signal alarm"),
    (0x13, "ENC2_SIGNAL", "AX2 module encoder 2 signal alarm"),
    (0x14, "ENC1_ZERO_CYCLE",
     "AX2 module encoder 1 zero-cycle alarm (zero mark not detected within 1.5 turns)"),
    (0x15, "ENC2_ZERO_CYCLE",
     "AX2 module encoder 2 zero-cycle alarm (zero mark not detected within 1.5 turns)"),
), unnamed=frozenset(range(0x10, 0x16)))

CODE_TABLES: dict[str, dict[int, AlarmCode]] = {COUPLER: COUPLER_CODES, MODULE: MODULE_CODES}


def is_resettable(table: str, code: int) -> bool:
    """§7 / §7.5: coupler codes above 0x7F are not resettable (a resync is needed)."""
    return table == MODULE or code <= LAST_RESETTABLE_COUPLER_CODE


def lookup(table: str, code: int) -> AlarmCode:
    """The row of ``code`` in ``table``; KeyError when the seed has no such code."""
    try:
        return CODE_TABLES[table][code]
    except KeyError:
        raise KeyError(f"no {table} alarm code {fmt_hex(code, 2)} in seed 000 "
                       f"{'§7.5' if table == COUPLER else '§7.6'}") from None


def by_name(name: str) -> AlarmCode:
    """A row by symbol, with or without ``CO_E_``, any case; KeyError when unknown."""
    wanted = name.strip().upper().removeprefix("CO_E_")
    for table in CODE_TABLES.values():
        for row in table.values():
            if row.symbol == wanted:
                return row
    raise KeyError(f"no alarm named {name!r}")


def parse_fault(text: str) -> AlarmCode:
    """What an operator wrote: a symbol (``TARATURA``) or ``coupler:0x04`` / ``module:0x0B``.

    A bare code is refused: both tables number from 0x01 and the same number means different
    alarms (0x04 is MISSING_NODE_ANSWER in §7.5 and ALARM_IO_FAULT in §7.6).
    """
    raw = str(text).strip()
    table, sep, rest = raw.partition(":")
    if sep:
        table = table.strip().lower()
        if table not in CODE_TABLES:
            raise CommandError(f"fault {raw!r}: the table is 'coupler' or 'module', "
                               f"not {table!r}")
        rest = rest.strip()
        try:
            code = int(rest, 0)
        except ValueError:
            row = _by_name_or_error(rest)
            if row.table != table:
                raise CommandError(f"fault {raw!r}: {row.symbol} is a {row.table} alarm") \
                    from None
            return row
        try:
            return lookup(table, code)
        except KeyError as exc:
            raise CommandError(f"fault {raw!r}: {exc.args[0]}") from None
    try:
        code = int(raw, 0)
    except ValueError:
        return _by_name_or_error(raw)
    found = [row.label + f" ({row.symbol})" for row in
             (CODE_TABLES[t].get(code) for t in TABLES) if row is not None]
    hint = " or ".join(found) if found else "neither table has it"
    raise CommandError(f"fault {raw!r} is a bare code, ambiguous between the coupler table "
                       f"(§7.5) and the module table (§7.6): write {hint}")


def _by_name_or_error(name: str) -> AlarmCode:
    try:
        return by_name(name)
    except KeyError:
        raise CommandError(f"unknown fault {name!r}: give a symbol of seed 000 §7.5 / §7.6 "
                           f"(e.g. MISSING_NODE_ANSWER, TARATURA) or coupler:0xNN / "
                           f"module:0xNN") from None


def emergency_data(table: str, code: int, module: int) -> bytes:
    """§7: byte 0 module number, byte 1 spare, byte 2 module code, byte 3 coupler code,
    byte 4 spare. A coupler code and a module code never appear together."""
    module_code = code if table == MODULE else 0
    coupler_code = code if table == COUPLER else 0
    return bytes((module & 0xFF, 0, module_code, coupler_code, 0))


def emergency_word(data: bytes) -> int:
    """0x5400 (§6.23): bytes 0..3 as a little-endian UDINT (address alarm -> 0x12000000)."""
    return int.from_bytes(data[:4], "little")


def manufacturer_al_status(table: str, code: int, module: int) -> int | None:
    """§7.7: 0x8000 | module number in byte 1 | coupler code in byte 0; None for an alarm of a
    table outside :data:`ESM_ALARM_TABLES` (a module alarm), which has no AL status code."""
    if table not in ESM_ALARM_TABLES:
        return None
    return AL_STATUS_MANUFACTURER | (module & 0xFF) << 8 | code


@dataclass(frozen=True)
class ManufacturerAlStatus:
    """A decoded §7.7 0x80XX code: the one reading of it every view uses."""

    module: int  # byte 1 (without the 0x80 of the area); 0: the coupler itself
    coupler: AlarmCode  # byte 0

    @property
    def text(self) -> str:
        """``module 2: coupler code 0x04 MISSING_NODE_ANSWER``."""
        where = f"module {self.module}" if self.module else "coupler"
        return f"{where}: coupler code {fmt_hex(self.coupler.code, 2)} {self.coupler.symbol}"


def decode_al_status(code: int) -> ManufacturerAlStatus | None:
    """§7.7: 0x8000 | module in byte 1 | coupler code in byte 0; None when ``code`` is no such
    code. Byte 0 = 0 (0x8N00) is none: a module alarm has no AL status code."""
    if code < AL_STATUS_MANUFACTURER or code > 0xFFFF:
        return None
    module, coupler_code = code >> 8 & 0x7F, code & 0xFF
    row = COUPLER_CODES.get(coupler_code)
    if module > MAX_MODULES or row is None:
        return None
    return ManufacturerAlStatus(module, row)


def al_status_meaning(code: int) -> str:
    """What an AL status code of this coupler means: a 0x80XX read by :func:`decode_al_status`,
    any other code by its ETG text. The model's own reading and the State tab's (from the
    snapshot) both come from here."""
    found = decode_al_status(code)
    return found.text if found is not None else describe_al_status_code(code)

# AL status code when a latched alarm makes the coupler refuse PREOP -> SAFEOP or SAFEOP -> OP.
# A configuration mismatch is what §7.7 0x0052 describes ("connection to an unexpected device.
# Perform an hardware configuration procedure"), 0xF030/0xF050 disagreeing is 0x0070; every
# other coupler alarm answers its 0x80XX code, as the §7.7 log shows for 0x8204. A module alarm
# refuses nothing (ESM_ALARM_TABLES).
REFUSAL_AL_STATUS: dict[tuple[str, int], int] = {
    (COUPLER, 0x01): 0x0052,
    (COUPLER, 0x02): 0x0052,
    (COUPLER, 0x14): 0x0070,
}


@dataclass(frozen=True)
class Alarm:
    """One alarm instance: which table, which code, which module (0 = none)."""

    table: str
    code: int
    module: int = 0

    @property
    def info(self) -> AlarmCode:
        return lookup(self.table, self.code)

    @property
    def data(self) -> bytes:
        return emergency_data(self.table, self.code, self.module)

    @property
    def word(self) -> int:
        return emergency_word(self.data)

    @property
    def holds_esm(self) -> bool:
        """It takes SAFEOP / OP to PREOP and bars them while latched (a coupler alarm)."""
        return self.table in ESM_ALARM_TABLES

    @property
    def al_status_code(self) -> int | None:
        return manufacturer_al_status(self.table, self.code, self.module)

    @property
    def refusal_code(self) -> int | None:
        """The AL status code a SAFEOP / OP request is refused with; None: not refused."""
        if not self.holds_esm:
            return None
        return REFUSAL_AL_STATUS.get((self.table, self.code), self.al_status_code)

    @property
    def resettable(self) -> bool:
        return is_resettable(self.table, self.code)
