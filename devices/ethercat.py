"""EtherCAT slave concepts shared by every slave model: ESM states and the AL status codes.

Sources: seed 000 §7.7 (the AL status code table, register 0x134, printed "AI Status Code"),
seed 001 §9.2 and seed 004 ch. 5 (ESM), digest §1.8 and §6.1.
"""

from __future__ import annotations

import enum
import struct


class AlState(enum.IntEnum):
    """ESM states with their AL control / AL status register encodings."""

    INIT = 0x01
    PREOP = 0x02
    BOOT = 0x03
    SAFEOP = 0x04
    OP = 0x08

    @property
    def label(self) -> str:
        return self.name


AL_STATE_MASK = 0x0F  # AL status bits 0..3: the state
AL_STATUS_ERROR_FLAG = 0x10  # AL status bit 4: "error indication" (0x12 = PREOP + error)


def al_status_name(value: int) -> str:
    """An AL status register (0x0130) in words: ``PREOP + error`` for 0x12."""
    state_bits = value & AL_STATE_MASK
    try:
        name = AlState(state_bits).name
    except ValueError:
        name = f"state 0x{state_bits:X}"
    return f"{name} + error" if value & AL_STATUS_ERROR_FLAG else name

# The states in seed 003's words ("Each slave will step through the following states"); BOOT
# is not in seed 003: ETG.1000.6 keeps it for a firmware update (seed 000 §7.7 0x0013).
AL_STATE_TEXT: dict[AlState, str] = {
    AlState.INIT: "initialization phase",
    AlState.PREOP: "pre operational, no data-exchange occur between master and slaves",
    AlState.BOOT: "bootstrap, for a firmware update only (ETG.1000.6, not in seed 003)",
    AlState.SAFEOP: "safe operational, only input data from slaves to the master are exchanged",
    AlState.OP: "operational, full data-exchange can happen",
}

# Transitions a master may request (ETG.1000.6 ESM); a request outside this set answers
# AL status code 0x0011 "Invalid requested state change".
ALLOWED_TRANSITIONS: frozenset[tuple[AlState, AlState]] = frozenset({
    (AlState.INIT, AlState.PREOP),
    (AlState.PREOP, AlState.SAFEOP),
    (AlState.PREOP, AlState.INIT),
    (AlState.SAFEOP, AlState.OP),
    (AlState.SAFEOP, AlState.PREOP),
    (AlState.SAFEOP, AlState.INIT),
    (AlState.OP, AlState.SAFEOP),
    (AlState.OP, AlState.PREOP),
    (AlState.OP, AlState.INIT),
})

# Seed 000 §7.7, verbatim text (typos of the seed kept only where they are the meaning).
AL_STATUS_CODES: dict[int, str] = {
    0x0000: "No error",
    0x0001: "Unspecified error",
    0x0002: "No Memory",
    0x0004: "Output/Input mapping is not valid for this hardware or software revision (0x1018:03)",
    0x0006: "Firmware and EEPROM do not match. Slave needs BOOT-INIT transition",
    0x0007: "Firmware update not successful. Old firmware still running",
    0x0011: "Invalid requested state change",
    0x0012: "Unknown requested state",
    0x0013: "Bootstrap not supported",
    0x0014: "No valid firmware",
    0x0015: "Invalid mailbox configuration (BOOT state)",
    0x0016: "Invalid mailbox configuration (PreOP state)",
    0x0017: "Invalid sync manager configuration",
    0x0018: "No valid inputs available",
    0x0019: "No valid outputs",
    0x001A: "Synchronization error",
    0x001B: "Sync manager watchdog",
    0x001C: "Invalid Sync Manager Types",
    0x001D: "Invalid Output Configuration",
    0x001E: "Invalid Input Configuration",
    0x001F: "Invalid Watchdog Configuration",
    0x0020: "Slave needs cold start",
    0x0021: "Slave needs INIT",
    0x0022: "Slave needs PREOP",
    0x0023: "Slave needs SAFEOP",
    0x0024: "Invalid Input Mapping",
    0x0025: "Invalid Output Mapping",
    0x0026: "Inconsistent Settings",
    0x0027: "FreeRun not supported",
    0x0028: "SyncMode not supported",
    0x0029: "FreeRun needs 3Buffer Mode",
    0x002A: "Background Watchdog",
    0x002B: "No Valid Inputs and Outputs",
    0x002C: "Fatal Sync Error",
    0x002D: "No Sync Error",
    0x002E: "EtherCAT cycle time smaller Minimum Cycle Time supported by slave",
    0x0030: "Invalid DC SYNCH Configuration",
    0x0031: "Invalid DC Latch Configuration",
    0x0032: "PLL Error",
    0x0033: "DC Sync IO Error",
    0x0034: "DC Sync Timeout Error",
    0x0035: "DC Invalid Sync Cycle Time",
    0x0036: "DC Sync0 Cycle Time",
    0x0037: "DC Sync1 Cycle Time",
    0x0041: "MBX_AOE",
    0x0042: "MBX_EOE",
    0x0043: "MBX_COE",
    0x0044: "MBX_FOE",
    0x0045: "MBX_SOE",
    0x004F: "MBX_VOE",
    0x0050: "EEPROM no access",
    0x0051: "EEPROM Error",
    0x0052: "External hardware not ready. The slave refused the state transition due to "
            "connection to an unexpected device. Perform an hardware configuration procedure.",
    0x0061: "In legacy identification mode (dip switch mapped to register 0x12) this error is "
            "returned if the EEPROM ID value does not match to dipswitch value",
    0x0070: "Detected Module Ident List (0xF030) and Configured Module Ident List (0xF050) "
            "does not match",
    0x0080: "The slave supply voltage is too low",
    0x0081: "The slave supply voltage is too high",
    0x0082: "The slave temperature is too low",
    0x0083: "The slave temperature is too high",
}

def sync_error_reached(counter: int, limit: int) -> bool:
    """The sync error of 0x10F1:2 (ETG.1020 "Sync Error Counter Limit"): the slave's missed-
    event counter has reached the limit. ETG's sample stack (SSC ecatappl.c) keeps the SM sync
    sequence valid only while the counter is below the limit, so the miss that brings it to
    the limit is the error. Every slave model asks this (hot paths write it out as ``>=``)."""
    return counter >= limit


def emergency_frame(code: int, register: int, data: bytes) -> bytes:
    """A CoE emergency as it travels in the mailbox: error code (little endian), error
    register, 5 manufacturer bytes (ETG.1000.6 / DS301; seed 000 §7, seed 002 §2.5.3)."""
    if len(data) > 5:
        raise ValueError(f"an emergency carries at most 5 data bytes, got {len(data)}")
    return struct.pack("<HB", code, register) + bytes(data).ljust(5, b"\x00")


def parse_emergency_frame(frame: bytes) -> tuple[int, int, bytes]:
    """(error code, error register, 5 data bytes) of an 8-byte emergency frame."""
    if len(frame) != 8:
        raise ValueError(f"an emergency frame has 8 bytes, got {len(frame)}")
    code, register = struct.unpack_from("<HB", frame)
    return code, register, bytes(frame[3:])


MANUFACTURER_AREA = 0x8000  # seed 000 §7.7: "Inizio dell'area manufacturer"


def describe_al_status_code(code: int) -> str:
    """Plain text for an AL status code, including the manufacturer area (0x8000..0xFFFF)."""
    if code in AL_STATUS_CODES:
        return AL_STATUS_CODES[code]
    if code >= MANUFACTURER_AREA:
        return "Manufacturer specific"
    return "Reserved"
