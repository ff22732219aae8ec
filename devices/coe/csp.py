"""Cyclic synchronous position (0x6060 = 8) from the CoE side.

Seed 004 ch. 5 lists "0x6060 per Cyclic Synchronous Position Mode (csp) = 8" among the modes
a master selects on EtherCAT, and nothing more; the drive model implements the interpolator
(mode 7: a position set-point per period, linear in between, taken at once on a Sync), not
CSP. CiA 402 CSP is that same machinery fed differently: the master sends a target position
(0x607A) every cycle and the drive follows it while Operation enabled, with no start bit.
So CSP is done here, on the CoE side, without touching the drive:

- 0x6060 = 8 puts the drive in mode 7 and remembers CSP; the interpolation set-point starts
  at the actual position, so enabling does not jump;
- 0x607A written in mode 7 is the drive's set-point already (R09 "scritto in modo 7");
- the controlword a CoE master writes reaches the drive with bit 4 (interpolation enable)
  set, and reads back as written;
- 0x6061 shows 8; any other mode written by anyone (Modbus, the panel) ends CSP.

The SM2 event of every cycle is the drive's Sync (SM-Synchron, ch. 5 "Settaggi SM / DC").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.servo.ds402 import CW_NEW_SET_POINT

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

CSP_MODE = 8
INTERPOLATED_MODE = 7
CSP_SUPPORTED = 0x0000_0080  # 0x6502 bit 7 (CiA 402): csp


class Csp:
    def __init__(self, drive: ServoDrive) -> None:
        self.drive = drive
        self.selected = False
        self.cw = 0  # the controlword as the master wrote it

    @property
    def active(self) -> bool:
        return self.selected and self.drive.powered and self.drive.mode == INTERPOLATED_MODE

    def write_mode(self, value: int) -> None:
        """0x6060 from a CoE master (SDO or RxPDO); refusals are the drive's SDO aborts."""
        od = self.drive.od
        if value != CSP_MODE:
            od.write(0x6060, 0, value)
            self.selected = False
            return
        if self.active:
            return
        od.write(0x6060, 0, INTERPOLATED_MODE)
        od.write(0x607A, 0, self.drive.position_user)  # the set-point starts where the axis is
        self.selected = True
        self.cw = self.drive.cw & ~CW_NEW_SET_POINT

    def mode_display(self) -> int:
        return CSP_MODE if self.active else self.drive.mode

    def write_controlword(self, value: int) -> None:
        if self.active:
            self.cw = value
            value |= CW_NEW_SET_POINT
        self.drive.od.write(0x6040, 0, value)

    def controlword(self) -> int:
        return self.cw if self.active else self.drive.cw
