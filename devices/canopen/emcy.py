"""Emergency messages, the error register 0x1001 and the error history 0x1003.

Seed 004 ch. 4 "Emergency Message": eight bytes — error code (2), error register (1), vendor
field (5); the code classes of DS 301 (2xxx current, 3xxx voltage, 4xxx temperature, 8xxx
monitoring, ...); the error register bits (0 generic, 1 current, 2 voltage, 3 temperature,
4 communication, 5 device profile, 7 manufacturer); "simultaneously with the emergency
message the device writes the error code into [1003]". The drive's 0x1003 has one entry (the
table prints sub 0 and sub 1 only) and sub 0 takes only 0, which clears sub 1 too.

A drive alarm is sent with its 0x603F code (ch. 5 table, :mod:`devices.servo.alarms`); the
vendor field carries the alarm number (R46) in its first byte. When the last alarm is reset
the drive sends the DS 301 "error reset" emergency 0x0000.
"""

from __future__ import annotations

import struct
from collections import deque
from dataclasses import dataclass, field

from devices.bitwords import BitWords

EMCY_BASE = 0x080
ERROR_RESET = 0x0000
LIFE_GUARD_ERROR = 0x8130  # DS 301: life guard error or heartbeat error
PDO_LENGTH_ERROR = 0x8210  # DS 301: PDO not processed due to length error
# Emergencies kept while they cannot leave (Stopped, inhibit time): a real node's EMCY buffer
# is finite too. The newest are kept; 32 holds every drive alarm (29) and an error reset.
EMCY_KEPT = 32

REG_GENERIC = 0x01
REG_CURRENT = 0x02
REG_VOLTAGE = 0x04
REG_TEMPERATURE = 0x08
REG_COMMUNICATION = 0x10
REG_PROFILE = 0x20
REG_MANUFACTURER = 0x80

REG_RESERVED = 0x40

# Error register 0x1001 bit names: DS 301's, as seed 004 ch. 4 prints them for the drive ("Bit
# Error cause"). The Codes tab reads the drive's register in these words, and a device whose
# seed names no bits (the TRS-CAT) in DS 301's; the CPX-E-EC has its own (seed 002 Tab. 22,
# devices/cpx/codes.py), the FastCAT one value (seed 000 §7, devices/fastcat/alarms.py).
REGISTER_BIT_NAMES: dict[int, str] = {
    REG_GENERIC: "Generic Error", REG_CURRENT: "Current", REG_VOLTAGE: "Voltage",
    REG_TEMPERATURE: "Temperature", REG_COMMUNICATION: "Communication Error",
    REG_PROFILE: "Device Profile Specific", REG_RESERVED: "Reserved (always 0)",
    REG_MANUFACTURER: "Manufacturer Specific",
}
REGISTER_WORDS = BitWords(REGISTER_BIT_NAMES)  # the views' reading of a 0x1001 value

# The DS 301 codes the node itself sends, in words (the Codes tab reads them, app/decoder.py).
EMCY_TEXT: dict[int, str] = {
    ERROR_RESET: "Error reset: no error is active any more",
    LIFE_GUARD_ERROR: "Life guard or heartbeat error: the master stopped guarding the node (no "
                      "guard request within life time factor x guard time)",
    PDO_LENGTH_ERROR: "PDO not processed: its length does not match the mapping",
}

# (first code, last code, error register bit): the DS 301 classes of the ch. 4 tables. Codes of
# other classes (50xx device hardware, 6xxx software, 70xx modules) set the generic bit only.
REGISTER_BIT_BY_CODE: tuple[tuple[int, int, int], ...] = (
    (0x2000, 0x2FFF, REG_CURRENT),
    (0x3000, 0x3FFF, REG_VOLTAGE),
    (0x4000, 0x4FFF, REG_TEMPERATURE),
    (0x8100, 0x82FF, REG_COMMUNICATION),  # 81xx communication, 82xx protocol
    (0x8300, 0x8FFF, REG_PROFILE),  # 86xx positioning (DSP 402), 87xx sync controller
    (0xFF00, 0xFFFF, REG_MANUFACTURER),
)


# Seed 004 ch. 4 "Emergency Message": "The high byte distinguishes the error categories" (10xx
# generic, 2XXX current, 3XXX voltage, 4XXX temperature, 50xx device hardware, 6XXX device
# software, 70xx additional modules, 8xxx monitoring, 90xx external error, F0xx additional
# functions, FFxx device specific). Keyed by the top nibble: the drive's own codes (0x5220,
# 0x5500, 0x7120, ...) are DSP 402's finer codes of the same categories. Fxxx splits on the
# whole high byte.
ERROR_CLASSES: dict[int, str] = {
    0x0: "Error reset / no error", 0x1: "Generic error", 0x2: "Current", 0x3: "Voltage",
    0x4: "Temperature", 0x5: "Device hardware", 0x6: "Device software",
    0x7: "Additional modules", 0x8: "Monitoring", 0x9: "External error",
    0xF: "Additional functions",
}
DEVICE_SPECIFIC_HIGH_BYTE = 0xFF


def error_class(code: int) -> str:
    """The category of an error code (its high byte), "" for one the seed's table lacks."""
    if code >> 8 == DEVICE_SPECIFIC_HIGH_BYTE:
        return "Device specific"
    return ERROR_CLASSES.get(code >> 12 & 0xF, "")


def register_bits(code: int) -> int:
    """Error register bits of one active error code (generic always)."""
    if code == ERROR_RESET:
        return 0
    for low, high, bit in REGISTER_BIT_BY_CODE:
        if low <= code <= high:
            return REG_GENERIC | bit
    return REG_GENERIC


def payload(code: int, register: int, vendor: bytes = b"") -> bytes:
    """The eight data bytes: code (little endian), register, five vendor bytes."""
    if len(vendor) > 5:
        raise ValueError("the vendor field is five bytes")
    return struct.pack("<HB", code, register) + vendor.ljust(5, b"\0")


@dataclass
class ErrorHistory:
    """0x1003 with one entry: sub 0 = number of errors (0/1), sub 1 = the latest."""

    latest: int = 0
    count: int = 0

    def record(self, code: int, info: int = 0) -> None:
        """DS 301 layout of an entry: error code in bits 0-15, additional info in 16-31."""
        self.latest = (info & 0xFFFF) << 16 | code
        self.count = 1

    @staticmethod
    def fields(entry: int) -> tuple[int, int]:
        """(error code, additional info) of an entry ``record`` wrote: the drive puts its alarm
        number in the info, so 0x00108611 is alarm 16 (0x10), code 0x8611."""
        return entry & 0xFFFF, entry >> 16 & 0xFFFF

    def clear(self) -> None:
        self.latest = self.count = 0


@dataclass
class EmcyProducer:
    """Emergencies waiting for the bus, spaced by the inhibit time 0x1015 (x 100 us), and
    held while the NMT state allows no EMCY (Stopped) until :meth:`release`."""

    inhibit_100us: int = 0
    last_sent_us: int | None = None
    pending: deque[tuple[bytes, int]] = field(default_factory=lambda: deque(maxlen=EMCY_KEPT))

    def queue(self, data: bytes, ready_us: int) -> None:
        self.pending.append((data, ready_us))

    def release(self, t_us: int) -> None:
        """The node may send EMCY again from ``t_us``: what it held leaves from then on, in
        the order raised (not back-dated to when each error came)."""
        self.pending = deque(((data, max(at, t_us)) for data, at in self.pending),
                             maxlen=EMCY_KEPT)

    def due(self, now_us: int) -> tuple[bytes, int] | None:
        """The next emergency and the instant it may leave, if that is by ``now_us``."""
        if not self.pending:
            return None
        data, at = self.pending[0]
        if self.last_sent_us is not None:
            at = max(at, self.last_sent_us + self.inhibit_100us * 100)
        if at > now_us:
            return None
        self.pending.popleft()
        self.last_sent_us = at
        return data, at
