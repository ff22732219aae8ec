"""Distributed-clock registers of an emulated ESC, enough for SOEM's `ecx_configdc()` / dcsync0.

What a master does (SOEM ethercatdc.c, read for behaviour):
1. BWR to 0x0900: every slave latches the local time the frame reached each port
   (0x0900 port 0, 0x0904 port 1, ...) and, 64-bit, at its processing unit (0x0918).
2. Per slave: reads 0x0900..0x090C and 0x0918, writes 0x0920 (system time offset, so that
   local + offset = master time) and 0x0928 (propagation delay it computed from the port times).
3. Cyclic: ARMW/FRMW on 0x0910 (system time) - the reference slave answers, the others take
   the value as the master's time; the difference lands in 0x092C.
4. dcsync0: writes 0x0981 (activation), 0x0990 (SYNC0 start, 64-bit), 0x09A0 (SYNC0 cycle).

All slaves of one wire process share one clock (process B's monotonic clock), so the emulated
line has no drift; the port times are offset by a fixed hop delay per slave so a master computes
plausible, increasing propagation delays.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable

from app.ethercat_wire import registers as R

HOP_NS = 400  # forward delay from one slave's port 0 to the next one's (cable + processing)
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
_DC_REPORTED = ((R.DC_ACTIVATION, 1), (R.DC_START_TIME0, 8), (R.DC_CYCLE0, 4))


class DcClock:
    """Local time in ns since the wire process started (all ESCs of the line share it)."""

    def __init__(self, now_ns: Callable[[], int] = time.monotonic_ns) -> None:
        self._now = now_ns
        self._t0 = now_ns()

    def local_ns(self) -> int:
        return self._now() - self._t0


def latch(mem: bytearray, local_ns: int, index: int, downstream: int) -> None:
    """A write to 0x0900 reached the slave at line index `index` with `downstream` slaves
    after it: latch the receive times of port 0, port 1 (the frame coming back) and the PU."""
    t0 = local_ns + index * HOP_NS
    _U32.pack_into(mem, R.DC_RECEIVE_TIME_PORT0, t0 & 0xFFFFFFFF)
    t1 = t0 + 2 * downstream * HOP_NS if downstream else 0
    _U32.pack_into(mem, R.DC_RECEIVE_TIME_PORT0 + 4, t1 & 0xFFFFFFFF)
    _U32.pack_into(mem, R.DC_RECEIVE_TIME_PORT0 + 8, 0)
    _U32.pack_into(mem, R.DC_RECEIVE_TIME_PORT0 + 12, 0)
    _U64.pack_into(mem, R.DC_RECEIVE_TIME_PU, t0 & 0xFFFFFFFFFFFFFFFF)


def system_time(mem: bytearray, local_ns: int) -> int:
    """Local time plus the offset the master wrote to 0x0920 (64-bit wrap)."""
    return (local_ns + _U64.unpack_from(mem, R.DC_SYSTEM_OFFSET)[0]) & 0xFFFFFFFFFFFFFFFF


def refresh_system_time(mem: bytearray, local_ns: int) -> None:
    """Put the current system time at 0x0910 before a read of it."""
    _U64.pack_into(mem, R.DC_SYSTEM_TIME, system_time(mem, local_ns))


def take_master_time(mem: bytearray, written: int, local_ns: int) -> None:
    """A master wrote its time to 0x0910: keep the difference at 0x092C (bit 31: the local
    copy is behind) as a real ESC's drift filter would see it; the emulated clock never drifts."""
    delay = _U32.unpack_from(mem, R.DC_SYSTEM_DELAY)[0]
    diff = (written + delay - system_time(mem, local_ns)) & 0xFFFFFFFF
    if diff & 0x80000000:
        diff = (-diff) & 0x7FFFFFFF
    else:
        diff = min(diff, 0x7FFFFFFF) | (0x80000000 if diff else 0)
    _U32.pack_into(mem, R.DC_SYSTEM_DIFF, diff)


def touches_sync(ado: int, end: int) -> bool:
    """Did a write [ado, end) touch one of the registers reported to process A?"""
    return any(ado < reg + size and end > reg for reg, size in _DC_REPORTED)


def sync_settings(mem: bytearray) -> dict[str, int]:
    """The ("dc", pos, {...}) payload: activation 0x0981, SYNC0 cycle 0x09A0, start 0x0990."""
    return {
        "activation": mem[R.DC_ACTIVATION],
        "sync0_cycle_ns": _U32.unpack_from(mem, R.DC_CYCLE0)[0],
        "start_time_ns": _U64.unpack_from(mem, R.DC_START_TIME0)[0],
    }
