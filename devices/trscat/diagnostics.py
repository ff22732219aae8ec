"""Application errors, the 0x10F3 diagnosis history (acknowledge mode, 20 messages), EMCY.

Seed 001 §9.3.7: the application error codes (DS301 / DS4xx emergency numbering), their
consequences (an internal hardware error shuts the TRS bus down for good, an internal software
error also sends the ESM back to PRE-OP and deadlocks it), 0x10F3 in acknowledge mode with up
to 20 messages, 0x10F3:5 flags (bits 1..3 disable info / warning / error messages) and
0x10F1:2. The message layout, the Diag Code ranges, flag bits 0 (send as emergency) and 5 (a
message discarded) and what a write of 0x10F3:3 does are ETG.1020's; the seed says the texts
are in the ESI file, which we do not have, so the Text IDs and texts are FieldRig's
(docs/trscat.md).
"""

from __future__ import annotations

import enum
import struct
from dataclasses import dataclass

from devices.bitwords import FlagWords
from devices.device import CommandError
from devices.names import did_you_mean
from devices.od import AbortCode, SdoAbort

# ETG.1020 Diag Code, bits 16..31: 0xE800 = a DS301 / DS4xx emergency code in bits 0..15,
# 0xE000 = manufacturer specific (FieldRig: the AL status code of an SM / DC check).
DIAG_CODE_EMERGENCY = 0xE800_0000
DIAG_CODE_MANUFACTURER = 0xE000_0000
MAX_MESSAGES = 20  # §9.3.7 "coda fino a 20 messaggi diagnostici"
FIRST_MESSAGE_SUB = 6  # ETG.1020: messages from sub 6
LAST_MESSAGE_SUB = FIRST_MESSAGE_SUB + MAX_MESSAGES - 1
FLAG_EMERGENCY = 0x0001  # ETG.1020 0x10F3:5 bit 0 (not printed in §9.3.7; default 0)
# ETG.1020 0x10F3:5 bit 5, the device's: in acknowledge mode a new message was discarded.
FLAG_OVERWRITE_DISCARD = 0x0020
FLAG_LOCAL_TIMESTAMP = 0x0010  # message flags bit 4: the time stamp is the device's own time
PARAM_UINT8 = 0x0005  # ETG.1020 parameter flags: data type UNSIGNED8
# bits 0..3; bit 4 (mode) is fixed: the TRS-CAT runs acknowledge mode; bit 5 is the device's
FLAGS_WRITABLE = 0x000F


class DiagType(enum.IntEnum):
    INFO = 0
    WARNING = 1
    ERROR = 2

    @property
    def disable_bit(self) -> int:
        """§9.3.7 0x10F3:5: Bit1 info, Bit2 warnings, Bit3 errors."""
        return 1 << (int(self) + 1)


# 0x10F3:5 in words, (bit = 1, bit = 0), for the Codes tab: §9.3.7 "Flag messaggi abilitati,
# default 0x00 tutti abilitati. Bit1 = 1: disabilita messaggi informativi, Bit2 = 1: ... di
# attenzione, Bit3 = 1: ... di errore"; bits 0 and 5 are ETG.1020's, which the model follows.
FLAG_TEXT: dict[int, tuple[str, str]] = {
    FLAG_EMERGENCY: ("each new application error also sent as a CoE emergency (ETG.1020; "
                     "§9.3.7 does not print bit 0)", "no emergency (ETG.1020)"),
    DiagType.INFO.disable_bit: ("info messages disabled", "info messages enabled"),
    DiagType.WARNING.disable_bit: ("warning messages disabled", "warning messages enabled"),
    DiagType.ERROR.disable_bit: ("error messages disabled", "error messages enabled"),
    FLAG_OVERWRITE_DISCARD: ("a new message discarded, 20 unacknowledged ones stored "
                             "(ETG.1020, set by the TRS-CAT)",
                             "no message discarded (ETG.1020)"),
}
FLAG_WORDS = FlagWords(FLAG_TEXT, "TRS-CAT")


class Bus(enum.Enum):
    """The 0xF100 TRS bus status a fault makes FALSE (§9.3.4 subs 2..4)."""

    NONE = "none"
    COMMUNICATION = "communication"  # 0xF100:2
    VOLTAGE = "voltage"  # 0xF100:3
    CURRENT = "current"  # 0xF100:4


class Target(enum.Enum):
    """Where a fault can be injected."""

    DEVICE = "device"  # the TRS-CAT itself
    SLOT = "slot"  # the TRS-CAT (slot 0) or an expansion
    ANALOG = "analog"  # a TRS-AN-E expansion only


@dataclass(frozen=True)
class AppFault:
    """One application error cause of §9.3.7 (two causes share 0x7100)."""

    name: str  # FieldRig symbol, used by inject_fault and in alarm events
    code: int  # §9.3.7 emergency code
    text: str  # English rendering of the seed's line
    register: int  # DS301 error register (0x1001) bits: 0 generic, 1 current, 2 voltage,
    # 4 communication, 7 manufacturer
    target: Target
    bus_shutdown: bool = False  # §9.3.7 "shutdown irreversibile del bus TRS"
    deadlock: bool = False  # §9.3.7 0x6100: ESM back to PRE-OP, deadlock
    # §9.2 PS "0xF030 = 0xF050": the error the slot configuration check gives. Raised above
    # PRE-OP (only an injection can) it takes the device back to PRE-OP as that check would
    # have left it, so LEDs and AL status tell the same as on a real TRS-CAT.
    config_check: bool = False
    bus_flag: Bus = Bus.NONE


# §9.3.7 "messaggi applicativi di errore".
FAULTS: dict[str, AppFault] = {f.name: f for f in (
    AppFault("CONFIG_ERROR", 0xA000, "Configuration error", 0x01, Target.DEVICE,
             config_check=True),
    AppFault("TRS_OVERCURRENT", 0x7100,
             "Internal hardware error: power error, TRS bus overcurrent", 0x03, Target.DEVICE,
             bus_shutdown=True, bus_flag=Bus.CURRENT),
    AppFault("TRS_UNDERVOLTAGE", 0x7100,
             "Internal hardware error: power error, TRS bus undervoltage", 0x05, Target.DEVICE,
             bus_shutdown=True, bus_flag=Bus.VOLTAGE),
    AppFault("TRS_COMM_ERROR", 0x7500,
             "Internal hardware error: communication error on the TRS bus", 0x11,
             Target.DEVICE, bus_shutdown=True, bus_flag=Bus.COMMUNICATION),
    AppFault("AN_PLUS_12V", 0x5114, "+12 V supply error on the AN-E module", 0x05,
             Target.ANALOG),
    AppFault("AN_MINUS_12V", 0x5115, "-12 V supply error on the AN-E module", 0x05,
             Target.ANALOG),
    AppFault("FIELD_SUPPLY", 0x3220,
             "+24 V field supply error on a TRS-nn-E module or on the base", 0x05, Target.SLOT),
    AppFault("SOFTWARE_ERROR", 0x6100, "Internal software error", 0x81, Target.DEVICE,
             bus_shutdown=True, deadlock=True, bus_flag=Bus.COMMUNICATION),
)}
APP_CODES: frozenset[int] = frozenset(f.code for f in FAULTS.values())


def parse_fault(text: str) -> AppFault:
    """A FieldRig symbol (``FIELD_SUPPLY``) or a §9.3.7 code (``0x3220``)."""
    raw = str(text).strip()
    try:
        code = int(raw, 0)
    except ValueError:
        found = FAULTS.get(raw.upper())
        if found is None:
            raise CommandError(f"unknown TRS-CAT fault {raw!r} (known: {', '.join(FAULTS)}, or "
                               f"a code of seed 001 §9.3.7){did_you_mean(raw, FAULTS)}") \
                from None
        return found
    rows = [f for f in FAULTS.values() if f.code == code]
    if not rows:
        codes = ", ".join(f"0x{c:04X}" for c in sorted(APP_CODES))
        raise CommandError(f"fault {raw!r}: seed 001 §9.3.7 has no code 0x{code:04X} "
                           f"(codes: {codes})")
    if len(rows) > 1:
        names = " or ".join(f.name for f in rows)
        raise CommandError(f"fault {raw!r}: 0x{code:04X} has two causes in §9.3.7, write "
                           f"{names}")
    return rows[0]


@dataclass(frozen=True)
class DiagMessage:
    """One ETG.1020 diagnosis message (0x10F3 sub 6..25)."""

    diag_code: int
    dtype: DiagType
    text_id: int
    timestamp_ns: int
    params: tuple[int, ...]  # UNSIGNED8 parameters (the slot)
    text: str

    def encode(self) -> bytes:
        """Diag Code U32, Flags U16 (type, local time stamp, parameter count in bits 8..15),
        Text ID U16, Time Stamp U64, then per parameter: flags U16 + value."""
        flags = int(self.dtype) | FLAG_LOCAL_TIMESTAMP | len(self.params) << 8
        head = struct.pack("<IHHQ", self.diag_code, flags, self.text_id, self.timestamp_ns)
        return head + b"".join(struct.pack("<HB", PARAM_UINT8, p & 0xFF) for p in self.params)

    @property
    def code(self) -> int:
        return self.diag_code & 0xFFFF

    def snapshot(self, sub: int) -> dict[str, object]:
        return {"sub": sub, "diag_code": f"0x{self.diag_code:08X}", "code": f"0x{self.code:04X}",
                "type": self.dtype.name.lower(), "text_id": f"0x{self.text_id:04X}",
                "t": self.timestamp_ns / 1e9, "params": list(self.params), "text": self.text,
                "bytes": self.encode().hex(" ").upper()}


def app_message(fault: AppFault, slot: int | None, timestamp_ns: int) -> DiagMessage:
    params = () if slot is None else (slot,)
    where = "" if slot is None else f" (slot {slot})"
    return DiagMessage(DIAG_CODE_EMERGENCY | fault.code, DiagType.ERROR, fault.code,
                       timestamp_ns, params, fault.text + where)


def check_message(al_code: int, text: str, timestamp_ns: int) -> DiagMessage:
    """A message of the SM / DC check (§9.3.7): the AL status code it refused or fell with."""
    return DiagMessage(DIAG_CODE_MANUFACTURER | al_code, DiagType.ERROR, al_code, timestamp_ns,
                       (), text)


def emergency_frame(fault: AppFault, slot: int | None, register: int) -> bytes:
    """8-byte CoE emergency: code (LE), error register, 5 bytes (byte 0 = slot, FieldRig).
    ``register`` is 0x1001 as it reads now (DS301: the EMCY carries the error register, the
    bits of every active error, not only those of ``fault``)."""
    data = bytes(((slot or 0) & 0xFF, 0, 0, 0, 0))
    return struct.pack("<HB", fault.code, register & 0xFF) + data


class DiagHistory:
    """0x10F3 in acknowledge mode (§9.3.7): a ring of 20 subs; an unacknowledged message is
    never overwritten, so a 21st message waiting for acknowledgement is dropped (``lost``,
    ETG.1020's flag bit 5)."""

    def __init__(self) -> None:
        self.flags = 0
        self.clear()

    def clear(self) -> None:
        self.messages: dict[int, DiagMessage] = {}
        self.order: list[int] = []  # subs, oldest first
        self.newest = 0  # 0x10F3:2 (0 = none)
        self.newest_ack = 0  # 0x10F3:3
        self.unacked = 0
        self.lost = 0

    @property
    def new_available(self) -> bool:
        """0x10F3:4, mapped in 0x1AFF:5 (§9.3.4)."""
        return self.unacked > 0

    def enabled(self, dtype: DiagType) -> bool:
        return not self.flags & dtype.disable_bit

    def add(self, message: DiagMessage) -> bool:
        """Store a message; False when disabled by the flags or dropped (queue full)."""
        if not self.enabled(message.dtype):
            return False
        if self.unacked >= MAX_MESSAGES:
            self.flags |= FLAG_OVERWRITE_DISCARD
            self.lost += 1
            return False
        sub = FIRST_MESSAGE_SUB if self.newest in (0, LAST_MESSAGE_SUB) else self.newest + 1
        if sub in self.messages:
            self.order.remove(sub)
            if sub == self.newest_ack:
                # ETG.1020: :3 names no message once its own is overwritten, or it would
                # equal :2 while the new one waits for acknowledgement.
                self.newest_ack = 0
        self.messages[sub] = message
        self.order.append(sub)
        self.newest = sub
        self.unacked += 1
        return True

    def acknowledge(self, sub: int) -> None:
        """A write of 0x10F3:3: that message and every older one are acknowledged; 0 deletes
        the acknowledged messages (ETG.1020, acknowledge mode). A message already acknowledged
        (older than the newest one acknowledged) changes nothing: no acknowledgement is taken
        back, so :3 stays "the newest message acknowledged" and :4 turns TRUE only for a new
        message (§9.3.7)."""
        if sub == 0:
            self._delete_acknowledged()
            return
        # ETG.1020's answers to a value naming no message: below the message subs too low,
        # past them too high, a message sub holding no message out of range.
        if sub < FIRST_MESSAGE_SUB:
            raise SdoAbort(AbortCode.VALUE_TOO_LOW, 0x10F3, 3)
        if sub > LAST_MESSAGE_SUB:
            raise SdoAbort(AbortCode.VALUE_TOO_HIGH, 0x10F3, 3)
        if sub not in self.messages:
            raise SdoAbort(AbortCode.VALUE_RANGE, 0x10F3, 3)
        unacked = len(self.order) - 1 - self.order.index(sub)
        if unacked >= self.unacked:
            return
        self.newest_ack = sub
        self.unacked = unacked
        self.flags &= ~FLAG_OVERWRITE_DISCARD

    def _delete_acknowledged(self) -> None:
        # The master has not seen the others: they stay in their subs (all 20 exist for good,
        # sub 0 = 25), so :2 still names the newest and the ring goes on after it.
        for sub in self.order[:len(self.order) - self.unacked]:
            del self.messages[sub]
        self.order = self.order[len(self.order) - self.unacked:]
        if not self.order:
            self.newest = 0
        self.newest_ack = 0
        self.flags &= ~FLAG_OVERWRITE_DISCARD

    def set_flags(self, value: int) -> None:
        # ETG.1020: bit 5 is read only, the master's write neither sets nor clears it.
        self.flags = value & FLAGS_WRITABLE | self.flags & FLAG_OVERWRITE_DISCARD

    def raw(self, sub: int) -> bytes:
        found = self.messages.get(sub)
        return found.encode() if found is not None else b""

    def snapshot(self) -> dict[str, object]:
        return {"newest": self.newest, "newest_acknowledged": self.newest_ack,
                "new_message_available": self.new_available, "flags": self.flags,
                "lost": self.lost,
                "messages": [self.messages[s].snapshot(s) for s in self.order]}
