"""CoE emergencies of the drive: its alarms with their 0x603F codes, in the mailbox.

Seed 004 ch. 5 "Codici allarmi specifici": "Ad ogni allarme corrisponderà un error code
segnalato nell'oggetto 0x603F sub0, il cui valore è determinato da specifica ethercat" (the
table is :mod:`devices.servo.alarms`). A CoE emergency is the CANopen one in a mailbox
(ETG.1000.6): error code (2 bytes, little endian), error register 0x1001, five vendor bytes —
so the frame is built as the CANopen node builds it (:mod:`devices.canopen.emcy`): the alarm
number in the first vendor byte, the DS 301 "error reset" 0x0000 when the last alarm goes.
The mailbox runs from PREOP on; an alarm raised before waits until then. The way to INIT
stops the mailbox (devices/esm.py): the frames the master has not read are lost, 0x1003 stays.
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING

from devices.canopen import emcy as em

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

QUEUE = 32  # emergencies kept for a master that does not read its mailbox


def error_register(drive: ServoDrive) -> int:
    """0x1001: the DS 301 class bits of every latched alarm's 0x603F code."""
    if not drive.powered:
        return 0
    table = drive.alarm_table
    reg = 0
    for code in drive.alarms.latched:
        reg |= em.register_bits(table[code].error_code_or_generic)
    return reg


class EmergencyMailbox:
    def __init__(self) -> None:
        self.known: list[int] = []
        self.pending: deque[bytes] = deque(maxlen=QUEUE)
        self.history = em.ErrorHistory()  # 0x1003
        self.sent = 0

    def reset(self) -> None:
        self.known = []
        self.pending.clear()
        self.history.clear()

    def stop(self) -> None:
        """The mailbox stops (any state -> INIT): what the master has not read is lost."""
        self.pending.clear()

    def watch(self, drive: ServoDrive) -> list[bytes]:
        """Frames for the alarms latched since the last call (and the error reset)."""
        latched = list(drive.alarms.latched) if drive.powered else []
        if latched == self.known:
            return []
        table = drive.alarm_table
        out = []
        for code in latched:
            if code not in self.known:
                error = table[code].error_code_or_generic
                self.history.record(error, code)
                out.append(em.payload(error, error_register(drive), bytes((code,))))
        if self.known and not latched:
            out.append(em.payload(em.ERROR_RESET, 0))
        self.known = latched
        self.pending.extend(out)
        self.sent += len(out)
        return out

    def take(self) -> list[bytes]:
        out = list(self.pending)
        self.pending.clear()
        return out
