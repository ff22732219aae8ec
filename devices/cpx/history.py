"""The diagnosis history, object 0x10F3 (seed 002 §2.5.2, Tab. 14, 18, 19; ETG.1020).

64 messages in subindices 6 ... 69, a ring. Sub 5 "Flags": bit 0 sends every new message also
as an emergency (Tab. 19), bit 4 chooses the mode (Tab. 18): 0 = Overwrite (the oldest message
is overwritten once 64 are stored), 1 = Acknowledge (with 64 unacknowledged messages new ones
are lost). Bits 1-3 (disable info / warning / error messages) and the device-owned bit 5
(an unacknowledged message overwritten, or a new one discarded) are ETG.1020's, which the
seed's object follows.
Sub 3 takes the subindex of the newest message the master acknowledges (that one and every
older one; one older than sub 3's changes nothing); writing 0 clears the history (in
Acknowledge mode only the acknowledged messages). "New Message Available" (sub 4) is TRUE
while the newest message is unread (Overwrite) or a message unacknowledged (Acknowledge).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from devices.bitwords import FlagWords
from devices.cpx.codes import DiagType
from devices.cpx.messages import DiagMessage
from devices.od import AbortCode, SdoAbort

INDEX = 0x10F3
MAX_MESSAGES = 64  # §2.5.2 / Tab. 14 sub 1
FIRST_SUB = 6
FLAG_EMERGENCY = 0x0001  # Tab. 19: bit 0
FLAG_DISABLE_INFO = 0x0002  # ETG.1020 bits 1-3
FLAG_DISABLE_WARNING = 0x0004
FLAG_DISABLE_ERROR = 0x0008
FLAG_ACKNOWLEDGE = 0x0010  # Tab. 18: bit 4
FLAG_OVERWRITE_DISCARD = 0x0020  # ETG.1020 bit 5, set by the device
WRITABLE_FLAGS = 0x001F
# Sub 5 in words, (bit = 1, bit = 0), for the Codes tab: Tab. 19 (bit 0), Tab. 18 (bit 4), the
# rest ETG.1020's.
FLAG_TEXT: dict[int, tuple[str, str]] = {
    FLAG_EMERGENCY: ("Emergency Message activated (Tab. 19): every new message is also sent "
                     "as an emergency", "Emergency Message deactivated (Tab. 19)"),
    FLAG_DISABLE_INFO: ("info messages disabled (ETG.1020)", "info messages stored (ETG.1020)"),
    FLAG_DISABLE_WARNING: ("warning messages disabled (ETG.1020)",
                           "warning messages stored (ETG.1020)"),
    FLAG_DISABLE_ERROR: ("error messages disabled (ETG.1020)",
                         "error messages stored (ETG.1020)"),
    FLAG_ACKNOWLEDGE: ("Acknowledge mode (Tab. 18): a message is acknowledged before a new one "
                       "may overwrite it (with 64 unacknowledged messages new ones are lost)",
                       "Overwrite mode (Tab. 18): once 64 messages are stored, new ones "
                       "overwrite the oldest"),
    FLAG_OVERWRITE_DISCARD: ("an unacknowledged message was overwritten or a new one "
                             "discarded (ETG.1020, set by the bus module)",
                             "no message overwritten or discarded (ETG.1020)"),
}
FLAG_WORDS = FlagWords(FLAG_TEXT, "CPX-E-EC")


def flags_error(value: int) -> str | None:
    """Why 0x10F3:5 cannot take ``value`` (a master's start-up write), or None."""
    if 0 <= value <= WRITABLE_FLAGS:
        return None
    shown = f"0x{value:04X}" if value >= 0 else str(value)
    return f"{shown}: 0x10F3:5 takes bits 0-4 (seed 002 Tab. 18, 19)"


DISABLE_FLAG: dict[DiagType, int] = {DiagType.INFO: FLAG_DISABLE_INFO,
                                     DiagType.WARNING: FLAG_DISABLE_WARNING,
                                     DiagType.ERROR: FLAG_DISABLE_ERROR}


@dataclass
class DiagHistory:
    flags: int = 0x0000  # Tab. 14: default 0x0000 (emergency off, Overwrite mode)
    slots: list[DiagMessage | None] = field(default_factory=lambda: [None] * MAX_MESSAGES)
    newest: int = 0  # subindex of the newest message, 0 = none
    acknowledged: int = 0  # subindex of the newest acknowledged message, 0 = none
    count: int = 0
    unread: bool = False  # the newest message not read yet
    lost: int = 0  # messages discarded in Acknowledge mode (for the view)

    @property
    def acknowledge_mode(self) -> bool:
        return bool(self.flags & FLAG_ACKNOWLEDGE)

    @property
    def new_message(self) -> bool:
        """Sub 4 in the mode in force (ETG.1020): Overwrite, the newest message is unread;
        Acknowledge, a message is unacknowledged (sub 2 != sub 3). Derived, not latched, so
        a switch of Tab. 18 bit 4 shows the other mode's answer at once."""
        if self.acknowledge_mode:
            return self.unacknowledged() > 0
        return self.unread

    @property
    def emergency_enabled(self) -> bool:
        return bool(self.flags & FLAG_EMERGENCY)

    @property
    def sub0(self) -> int:
        """Highest subindex in use (5 with an empty history, as ETG.1020 counts it)."""
        return FIRST_SUB - 1 + self.count

    def unacknowledged(self) -> int:
        if self.count == 0:
            return 0
        if self.acknowledged == 0:
            return self.count
        return (self.newest - self.acknowledged) % MAX_MESSAGES

    def add(self, message: DiagMessage) -> bool:
        """Store a new message; False when the flags filter it or Acknowledge mode is full."""
        if self.flags & DISABLE_FLAG[message.dtype]:
            return False
        if self.acknowledge_mode and self.unacknowledged() >= MAX_MESSAGES:
            self.flags |= FLAG_OVERWRITE_DISCARD  # Tab. 18: "new messages ... are lost"
            self.lost += 1
            return False
        pos = 0 if self.count == 0 else (self.newest - FIRST_SUB + 1) % MAX_MESSAGES
        if self.slots[pos] is not None:
            # The oldest goes; unacknowledged only when none is acknowledged. ETG.1020's bit 5
            # in Overwrite mode reports that loss, not messages the master acknowledged.
            if not self.acknowledge_mode and not self.acknowledged:
                self.flags |= FLAG_OVERWRITE_DISCARD
            if self.acknowledged == FIRST_SUB + pos:
                self.acknowledged = 0
        self.slots[pos] = message
        self.newest = FIRST_SUB + pos
        self.count = min(MAX_MESSAGES, self.count + 1)
        self.unread = True
        return True

    def message(self, sub: int) -> DiagMessage | None:
        if not FIRST_SUB <= sub < FIRST_SUB + MAX_MESSAGES:
            raise SdoAbort(AbortCode.NO_SUBINDEX, INDEX, sub)
        return self.slots[sub - FIRST_SUB]

    def read(self, sub: int) -> DiagMessage | None:
        """A master's read of a message subindex (the side effect of ETG.1020)."""
        if sub > self.sub0:
            raise SdoAbort(AbortCode.NO_SUBINDEX, INDEX, sub)
        found = self.message(sub)
        if sub == self.newest:
            self.unread = False
        return found

    def write_acknowledged(self, value: int) -> None:
        if value == 0:
            self._clear()
            return
        # ETG.1020's answers: below the message subs too low, past them too high, a message
        # sub that holds no message out of range.
        if value < FIRST_SUB:
            raise SdoAbort(AbortCode.VALUE_TOO_LOW, INDEX, 3)
        if value >= FIRST_SUB + MAX_MESSAGES:
            raise SdoAbort(AbortCode.VALUE_TOO_HIGH, INDEX, 3)
        if value > self.sub0:
            raise SdoAbort(AbortCode.VALUE_RANGE, INDEX, 3)
        if self.acknowledged and (self.newest - value) % MAX_MESSAGES > self.unacknowledged():
            # Older than the newest acknowledged: already acknowledged (ETG.1020: a write
            # acknowledges that message and every older one), and nothing takes an
            # acknowledgement back, or the newer messages would be unacknowledged again.
            return
        self.acknowledged = value
        self.flags &= ~FLAG_OVERWRITE_DISCARD

    def write_flags(self, value: int) -> None:
        if value & ~(WRITABLE_FLAGS | FLAG_OVERWRITE_DISCARD):
            raise SdoAbort(AbortCode.VALUE_RANGE, INDEX, 5)
        self.flags = (value & WRITABLE_FLAGS) | (self.flags & FLAG_OVERWRITE_DISCARD)

    def ordered(self) -> list[tuple[int, DiagMessage]]:
        """(subindex, message), oldest first."""
        if self.count == 0:
            return []
        start = (self.newest - FIRST_SUB + 1) % MAX_MESSAGES if self.count == MAX_MESSAGES \
            else 0
        out = []
        for k in range(self.count):
            pos = (start + k) % MAX_MESSAGES
            message = self.slots[pos]
            assert message is not None
            out.append((FIRST_SUB + pos, message))
        return out

    def _clear(self) -> None:
        # ETG.1020: Acknowledge mode deletes the acknowledged messages only (none, if none
        # was): the master has not seen the others. Overwrite mode deletes them all.
        keep: list[DiagMessage] = []
        if self.acknowledge_mode:
            keep = [m for _sub, m in self.ordered()[self.count - self.unacknowledged():]]
        self.slots = [None] * MAX_MESSAGES
        for pos, message in enumerate(keep):
            self.slots[pos] = message
        self.count = len(keep)
        self.newest = FIRST_SUB + len(keep) - 1 if keep else 0
        self.acknowledged = 0
        self.unread = self.unread and bool(keep)
        self.flags &= ~FLAG_OVERWRITE_DISCARD

    def snapshot(self) -> dict[str, object]:
        return {"flags": self.flags, "mode": "acknowledge" if self.acknowledge_mode
                else "overwrite", "emergency": self.emergency_enabled,
                "newest": self.newest, "acknowledged": self.acknowledged,
                "new_message": self.new_message, "count": self.count, "lost": self.lost,
                "overwrite_discard": bool(self.flags & FLAG_OVERWRITE_DISCARD),
                "messages": [{"sub": sub, "type": m.dtype.name.lower(),
                              "text_id": f"0x{m.text_id:04X}", "text": m.text(),
                              "t_ns": m.timestamp_ns, "bytes": m.encode().hex(" ").upper()}
                             for sub, m in self.ordered()]}
